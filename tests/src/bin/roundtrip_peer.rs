//! A node process that echoes every metrocell message type: what arrives typed on
//! `/roundtrip/in/<pkg>/<Type>` is published back, re-serialised from the typed struct, on
//! `/roundtrip/out/<pkg>/<Type>`. Used by tests/system/dds_roundtrip.rs.

use std::time::Duration;

use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode, NodeError};

trait Echo {
    fn pump(&self) -> usize;
}

struct Typed<T: RosMessage> {
    sub: metrocell_node::Subscription<T>,
    publisher: metrocell_node::Publisher<T>,
}

impl<T: RosMessage> Echo for Typed<T> {
    fn pump(&self) -> usize {
        let mut n = 0;
        while let Ok(Some((m, _))) = self.sub.take() {
            let _ = self.publisher.publish(m);
            n += 1;
        }
        n
    }
}

/// The topic suffix of a type: `metrocell_msgs/msg/TrackerMeasurement` → `metrocell_msgs/TrackerMeasurement`.
pub fn suffix(ros_type: &str) -> String {
    ros_type.replace("/msg/", "/")
}

fn echo<T: RosMessage>(node: &mut MetrocellNode) -> Result<Box<dyn Echo>, NodeError> {
    let s = suffix(T::ROS_TYPE);
    Ok(Box::new(Typed::<T> {
        sub: node.subscription::<T>(&format!("/roundtrip/in/{s}"), qos::reliable())?,
        publisher: node.publisher::<T>(&format!("/roundtrip/out/{s}"), qos::reliable())?,
    }))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("roundtrip_peer", vec![])?;
    let mut echoes: Vec<Box<dyn Echo>> = Vec::new();
    macro_rules! each {
        ($t:ty) => {
            echoes.push(echo::<$t>(&mut node)?);
        };
    }
    metrocell_msgs::for_each_message!(each);
    node.info(format!("echoing {} message types", echoes.len()));
    let token = node.shutdown_token();
    while !token.wait_timeout(Duration::from_millis(2)) {
        for e in &echoes {
            e.pump();
        }
    }
    Ok(())
}
