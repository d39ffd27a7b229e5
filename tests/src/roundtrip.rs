//! Round trips of every metrocell message type through the `roundtrip_peer` node process (a
//! sample with every field non-default goes out on `/roundtrip/in/<pkg>/<Type>`, must come back
//! equal on `/roundtrip/out/<pkg>/<Type>`): used plain (tests/system/dds_roundtrip.rs) and
//! secured (tests/system/security.rs).

use std::time::{Duration, Instant};

use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode};

pub fn sample<T: RosMessage>(seed: u64) -> T {
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

/// Send a sample of `T` until it comes back (30 s), and compare.
pub fn roundtrip<T: RosMessage>(node: &mut MetrocellNode, seed: u64) -> Result<(), String> {
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

/// Round-trip every message type; the failures, one line each, and how many types were checked.
pub fn roundtrip_every_type(node: &mut MetrocellNode, seed: u64) -> (Vec<String>, usize) {
    let mut failures = Vec::new();
    let mut checked = 0;
    macro_rules! each {
        ($t:ty) => {
            checked += 1;
            if let Err(e) = roundtrip::<$t>(node, seed) {
                failures.push(e);
            }
        };
    }
    metrocell_msgs::for_each_message!(each);
    (failures, checked)
}
