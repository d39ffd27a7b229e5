#!/bin/sh
# Long cell-like load recorded through DDS (the recording issue's 10-minute run) on a bounded disk.
#
# The load writes ~60 MB/s (30 Hz 1920x1080 noise images do not compress), so 10 minutes would
# need ~35 GB. The recorder splits the bag every SPLIT seconds; each split file that the recorder
# has closed (every file but the newest two) is read back with `metrocell bag info` — which
# validates it — its per-topic counts are added up, and the file is deleted. At the end the
# remaining files are counted the same way, and totals are compared with what was published.
#
# Usage (inside the isolated namespace):
#   tests/isolated sh nodes/recorder/bench_cell_load_long.sh SECONDS BINDIR [SPLIT]
set -e
S=${1:-600}; BIN=${2:-target/release}; SPLIT=${3:-60}; OUT=/tmp/bench_cell_long_$$
COUNTS=$OUT.counts
: > "$COUNTS"
$BIN/metrocell-recorder --ros-args -p output:=$OUT -p compression:=zstd -p max_bag_duration:=$SPLIT &
REC=$!
sleep 1
$BIN/examples/cell_load_publisher --seconds "$S" > $OUT.published &
PUB=$!

# Append "topic count" lines of one .mcap file to $COUNTS; fail loudly on an unreadable file.
count_file() {
  # bag info reads tolerantly and exits 0 when it lists problems: treat a listed problem as a failure too
  if ! $BIN/metrocell bag info "$1" > $OUT.info 2>&1 || grep -q "Problem" $OUT.info; then
    echo "UNREADABLE: $1"; cat $OUT.info; exit 1
  fi
  sed -n 's/.*Topic: *\([^ |]*\) *| Type: [^|]*| Count: \([0-9]*\).*/\1 \2/p' $OUT.info >> "$COUNTS"
}

prune_closed() {
  for f in $(ls "$OUT"/*.mcap 2>/dev/null | sort -V | head -n -2); do
    count_file "$f"; rm -f "$f"
  done
}

T=0
while kill -0 $PUB 2>/dev/null; do
  echo "t=${T}s recorder RSS $(grep VmRSS /proc/$REC/status | awk '{print $2}') kB, disk $(du -sm $OUT | cut -f1) MB"
  prune_closed
  sleep 10; T=$((T+10))
done
wait $PUB || true
sleep 2
kill -INT $REC; wait $REC || true
for f in "$OUT"/*.mcap; do count_file "$f"; done
echo "published: $(cat $OUT.published)"
echo "recorded (sum over split files):"
awk '{c[$1]+=$2} END {for (t in c) print "  " t, c[t]}' "$COUNTS" | sort
rm -rf "$OUT" "$OUT".*
