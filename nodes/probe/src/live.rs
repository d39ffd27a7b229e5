//! The node on live DDS. Nominals pair with triggers by header stamp (see `processing`), so the
//! order in which a cycle takes them does not matter.

use std::time::Duration;

use metrocell_msgs::geometry_msgs::msg::PointStamped;
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit};
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_node::{qos, MetrocellNode};
use metrocell_probe_node::processing::ProbeProcessor;

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let mut processor = ProbeProcessor::from_parameters(node.parameters())?;
    let triggers = node.subscription::<JointState>("probe/trigger", qos::reliable())?;
    let nominals = node.subscription::<PointStamped>("probe/nominal", qos::reliable())?;
    let hits = node.publisher::<ProbeHit>("probe/hits", qos::reliable())?;
    let points = node.publisher::<MeasuredPoint>("measured_points", qos::reliable())?;
    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    while !token.is_triggered() {
        while let Ok(Some((n, _))) = nominals.take() {
            processor.nominal(n);
        }
        while let Ok(Some((t, _))) = triggers.take() {
            match processor.trigger(&t) {
                Ok((hit, point)) => {
                    let _ = hits.publish(hit);
                    if let Some(p) = point {
                        let _ = points.publish(p);
                        diagnostics.add_count("points_published", 1);
                    }
                    diagnostics.add_count("triggers", 1);
                    diagnostics.ok(format!("{} hits", processor.count()));
                }
                Err(e) => {
                    diagnostics.add_count("triggers_rejected", 1);
                    node.warn(e);
                }
            }
        }
        token.wait_timeout(Duration::from_millis(2));
    }
    Ok(())
}
