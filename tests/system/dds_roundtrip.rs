//! Two node processes exchange every metrocell message type over DDS: this test publishes a
//! sample with every field non-default, the `roundtrip_peer` process (a separate node process)
//! receives it typed and publishes it back, and what returns must equal what was sent, field for
//! field.

use std::process::Command;
use std::time::{Duration, Instant};

use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode};
use system_tests::{bin, require_isolated_network, ChildGuard};

fn sample<T: RosMessage>(seed: u64) -> T {
    // a type with one small field (std_msgs/Bool) can draw its default: try the next seeds
    for s in seed..seed + 16 {
        let v = rosmsg::sample_value(metrocell_msgs::registry(), T::ROS_TYPE, s).unwrap();
        let json = rosmsg::to_json(&v);
        if json.as_object().is_some_and(|o| o.is_empty()) {
            // a message with no fields (constants only, e.g. rcl_interfaces/msg/ParameterType):
            // the default is the only value it has; the round trip still checks it arrives
            return T::default();
        }
        let typed: T = serde_json::from_value(json).unwrap();
        if typed != T::default() {
            return typed;
        }
    }
    panic!(
        "{}: no sample in 16 seeds differs from the default",
        T::ROS_TYPE
    );
}

fn roundtrip<T: RosMessage>(node: &mut MetrocellNode, seed: u64) -> Result<(), String> {
    let s = T::ROS_TYPE.replace("/msg/", "/");
    let publisher = node
        .publisher::<T>(&format!("/roundtrip/in/{s}"), qos::reliable())
        .unwrap();
    let sub = node
        .subscription::<T>(&format!("/roundtrip/out/{s}"), qos::reliable())
        .unwrap();
    let sent = sample::<T>(seed);
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut next_send = Instant::now();
    while Instant::now() < deadline {
        // Resend until the peer's reader has matched ours; duplicates are identical anyway.
        if Instant::now() >= next_send {
            publisher
                .publish(sent.clone())
                .map_err(|e| format!("{}: publish: {e:?}", T::ROS_TYPE))?;
            next_send += Duration::from_millis(250);
        }
        if let Ok(Some((back, _))) = sub.take() {
            return if back == sent {
                Ok(())
            } else {
                Err(format!(
                    "{}: came back different:\nsent {sent:?}\ngot  {back:?}",
                    T::ROS_TYPE
                ))
            };
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    Err(format!("{}: nothing came back within 30 s", T::ROS_TYPE))
}

#[test]
fn every_message_type_survives_a_round_trip_through_another_node_process() {
    require_isolated_network();
    let _peer = ChildGuard::spawn(&mut Command::new(bin("roundtrip_peer")));
    let mut node = MetrocellNode::builder("roundtrip_test")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let mut failures = Vec::new();
    let mut checked = 0;
    macro_rules! each {
        ($t:ty) => {
            checked += 1;
            if let Err(e) = roundtrip::<$t>(&mut node, 11) {
                failures.push(e);
            }
        };
    }
    metrocell_msgs::for_each_message!(each);
    assert!(checked >= 31, "only {checked} types checked");
    assert!(
        failures.is_empty(),
        "{} of {checked} types failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
