"""Count the UDP datagrams on the loopback that carry each marker in clear text.

A passive eavesdropper on the cell's network, for tests/system/security.rs: a raw packet socket on
`lo` (root inside the test's network namespace) reads every datagram for SECONDS and prints, as
JSON, how many datagrams there were and how many held each MARKER's bytes.

    python sniff_udp.py SECONDS MARKER...
"""

import json
import socket
import sys
import time

ETH_P_ALL = 0x0003


def main() -> None:
    seconds = float(sys.argv[1])
    markers = [m.encode() for m in sys.argv[2:]]
    s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    s.bind(("lo", 0))
    s.settimeout(0.2)
    counts = {m.decode(): 0 for m in markers}
    datagrams = 0
    end = time.monotonic() + seconds
    print("listening", file=sys.stderr, flush=True)
    while time.monotonic() < end:
        try:
            frame, _ = s.recvfrom(1 << 16)
        except socket.timeout:
            continue
        # Ethernet header (14 bytes), IPv4 with protocol 17 = UDP
        if len(frame) < 34 or frame[12:14] != b"\x08\x00" or frame[23] != 17:
            continue
        datagrams += 1
        for m in markers:
            if m in frame:
                counts[m.decode()] += 1
    print(json.dumps({"datagrams": datagrams, "with_marker": counts}))


if __name__ == "__main__":
    main()
