//! A stalled or vanished publisher is reported on `/diagnostics` within the configured time
//! (issue 31, item 2), inside tests/isolated: the tracker node with `input_timeout:=1.0` gets
//! readings from `metrocell topic pub`; the publisher is killed; its input's status
//! (`/tracker: /tracker/measurements`) turns WARN "stalled or went away" within the timeout and
//! the heartbeat's second, and back to OK "receiving" when a publisher returns. An input that never
//! had a publisher (`/machine/commanded_joint_states` here) is said to have had none.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test input_watch -- --nocapture`

use std::time::{Duration, Instant};

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_node::{qos, MetrocellNode};
use system_tests::{bin, piped, require_isolated_network, ChildGuard};

const DOMAIN: &str = "93";

fn readings() -> ChildGuard {
    ChildGuard::spawn(
        piped(bin("metrocell"))
            .args(["topic", "pub", "/tracker/measurements", "metrocell_msgs/msg/TrackerMeasurement"])
            .arg("{target_id: smr1, point: {x: 1.0, y: 0.5, z: 0.2}, range: 1.14, covariance: [1e-10, 0, 0, 0, 1e-10, 0, 0, 0, 1e-10]}")
            .args(["--rate", "20"])
            .env("ROS_DOMAIN_ID", DOMAIN),
    )
}

/// Waits up to `within` for the status named `name` to have `level` (0 OK, 1 WARN, 2 ERROR) and a message containing
/// `says`; returns when it did, or panics with the last status seen.
fn wait_status(
    diagnostics: &metrocell_node::Subscription<DiagnosticArray>,
    name: &str,
    level: u8,
    says: &str,
    within: Duration,
) -> Instant {
    let deadline = Instant::now() + within;
    let mut last = String::from("none");
    while Instant::now() < deadline {
        while let Ok(Some((m, _))) = diagnostics.take() {
            for s in m.status.iter().filter(|s| s.name == name) {
                last = format!("level {} '{}'", s.level, s.message);
                if s.level == level && s.message.contains(says) {
                    return Instant::now();
                }
            }
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    panic!("{name}: no level {level} saying '{says}' within {within:?}; last: {last}");
}

#[test]
fn a_vanished_publisher_is_reported_within_the_timeout_and_its_return_too() {
    require_isolated_network();
    std::env::set_var("ROS_DOMAIN_ID", DOMAIN);
    let mut node = MetrocellNode::builder("input_watch_test").build().unwrap();
    let diagnostics = node
        .subscription::<DiagnosticArray>("/diagnostics", qos::reliable())
        .unwrap();
    let _tracker = ChildGuard::spawn(
        piped(bin("metrocell-tracker"))
            .args(["--ros-args", "-p", "input_timeout:=1.0"])
            .env("ROS_DOMAIN_ID", DOMAIN),
    );
    let readings_status = "/tracker: /tracker/measurements";
    // nothing published on the commanded joints at all
    wait_status(
        &diagnostics,
        "/tracker: /machine/commanded_joint_states",
        1,
        "nothing has been published on it yet",
        Duration::from_secs(30),
    );
    let publisher = readings();
    wait_status(
        &diagnostics,
        readings_status,
        0,
        "receiving",
        Duration::from_secs(30),
    );
    std::thread::sleep(Duration::from_secs(2));
    drop(publisher); // SIGKILL: the publisher vanishes
    let gone = Instant::now();
    let seen = wait_status(
        &diagnostics,
        readings_status,
        1,
        "stalled or went away",
        Duration::from_secs(10),
    );
    let after = seen - gone;
    println!(
        "silence reported {:.2} s after the publisher was killed",
        after.as_secs_f64()
    );
    // the timeout (1 s), the heartbeat's period (1 s) and DDS's delivery
    assert!(after < Duration::from_millis(2600), "{after:?}");
    assert!(
        after > Duration::from_millis(900),
        "{after:?}: before the timeout"
    );
    let _back = readings();
    wait_status(
        &diagnostics,
        readings_status,
        0,
        "receiving",
        Duration::from_secs(30),
    );
}
