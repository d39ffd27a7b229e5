//! What DDS Security costs: the same stream between two participants of this process, plain and
//! then secured with sros2's governance (authentication, every RTPS message and every payload
//! encrypted, access control), paired in one run so that the machine's load is shared.
//!
//! For each message size, each mode publishes `--seconds` of messages at `--rate` Hz (reliable,
//! keep-last 1000) while the same thread takes what arrives, and reports what was delivered and
//! the process's CPU time (both participants' DDS threads included) per message, then the ratio
//! secured / plain. Keys are exchanged before the clock starts.
//!
//!   cargo build --release -p metrocell-node --example secured_throughput
//!   tests/isolated target/release/examples/secured_throughput [--seconds 5] [--rate 2000]

use std::path::Path;
use std::time::{Duration, Instant};

use metrocell_msgs::std_msgs::msg::String as RosString;
use metrocell_node::{qos, DdsEnvironment, DiscoveryRange, MetrocellNode};
use metrocell_security::SecurityEnvironment;

const DOMAIN: u16 = 117;

fn arg(name: &str, default: f64) -> f64 {
    std::env::args()
        .skip_while(|a| a != name)
        .nth(1)
        .map_or(default, |v| v.parse().expect("a number"))
}

/// User + system CPU seconds of this process so far (/proc/self/stat, clock ticks of 10 ms).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    // the fields after the command's closing parenthesis: utime and stime are the 12th and 13th
    let after = &stat[stat.rfind(')').expect("stat format") + 2..];
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    ticks / 100.0
}

fn node(name: &str, secured: Option<(&Path, &str)>) -> MetrocellNode {
    let mut b = MetrocellNode::builder(name)
        .diagnostics_period(None)
        .handle_signals(false)
        .environment(DdsEnvironment {
            domain_id: DOMAIN,
            discovery_range: DiscoveryRange::Localhost,
        });
    b = match secured {
        Some((keystore, enclave)) => b.security(SecurityEnvironment {
            enabled: true,
            enforce: true,
            keystore: Some(keystore.to_path_buf()),
            enclave_override: Some(enclave.into()),
        }),
        None => b.security(SecurityEnvironment::default()),
    };
    b.build().expect("node")
}

struct Outcome {
    sent: u64,
    received: u64,
    cpu_per_message_us: f64,
}

fn stream(secured: Option<&Path>, bytes: usize, seconds: f64, rate: f64) -> Outcome {
    let topic = format!("/throughput_{bytes}");
    let mut talker = node("throughput_talker", secured.map(|k| (k, "/bench/talker")));
    let mut listener = node(
        "throughput_listener",
        secured.map(|k| (k, "/bench/listener")),
    );
    let q = qos::reliable().history(ros2_client::qos::History::KeepLast { depth: 1000 });
    let publisher = talker.publisher::<RosString>(&topic, q.clone()).unwrap();
    let subscription = listener.subscription::<RosString>(&topic, q).unwrap();
    let message = RosString {
        data: "x".repeat(bytes),
    };
    // matched and keys exchanged: a first message has gone through
    let ready = Instant::now();
    'warm: while ready.elapsed() < Duration::from_secs(30) {
        let _ = publisher.publish(message.clone());
        for _ in 0..20 {
            if let Ok(Some(_)) = subscription.take() {
                break 'warm;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    assert!(
        ready.elapsed() < Duration::from_secs(30),
        "no message arrived within 30 s (run inside tests/isolated)"
    );
    std::thread::sleep(Duration::from_millis(300));
    while let Ok(Some(_)) = subscription.take() {}
    let period = Duration::from_secs_f64(1.0 / rate);
    let cpu0 = cpu_seconds();
    let start = Instant::now();
    let (mut sent, mut received) = (0u64, 0u64);
    while start.elapsed().as_secs_f64() < seconds {
        let due = start + period * sent as u32;
        if Instant::now() >= due {
            if publisher.publish(message.clone()).is_ok() {
                sent += 1;
            }
        } else {
            std::thread::sleep(due - Instant::now());
        }
        while let Ok(Some(_)) = subscription.take() {
            received += 1;
        }
    }
    // what is still on its way
    let drain = Instant::now();
    while received < sent && drain.elapsed() < Duration::from_secs(2) {
        match subscription.take() {
            Ok(Some(_)) => received += 1,
            _ => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    let cpu = cpu_seconds() - cpu0;
    Outcome {
        sent,
        received,
        cpu_per_message_us: cpu / sent.max(1) as f64 * 1e6,
    }
}

fn main() {
    let seconds = arg("--seconds", 5.0);
    let rate = arg("--rate", 2000.0);
    let dir = std::env::temp_dir().join(format!("secured_throughput_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let keystore = dir.join("keystore");
    metrocell_security::keystore::create_keystore(&keystore, DOMAIN).expect("keystore");
    for enclave in ["/bench/talker", "/bench/listener"] {
        metrocell_security::keystore::create_enclave(&keystore, enclave).expect("enclave");
    }
    println!("{seconds} s at {rate} Hz per run, reliable keep-last 1000, two participants in this process");
    println!("| payload | mode | delivered | CPU per message | secured / plain |");
    println!("|---|---|---|---|---|");
    for bytes in [200usize, 16_384] {
        let plain = stream(None, bytes, seconds, rate);
        let secured = stream(Some(&keystore), bytes, seconds, rate);
        for (mode, o) in [("plain", &plain), ("secured", &secured)] {
            let ratio = if mode == "secured" {
                format!(
                    "{:.2}×",
                    secured.cpu_per_message_us / plain.cpu_per_message_us
                )
            } else {
                String::new()
            };
            println!(
                "| {bytes} B | {mode} | {} of {} | {:.1} µs | {ratio} |",
                o.received, o.sent, o.cpu_per_message_us
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
