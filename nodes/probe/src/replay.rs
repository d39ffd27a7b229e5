//! The node on a bag (`--bag IN_BAG`): no DDS. `probe/nominal` and `probe/trigger` are read in
//! log-time order and paired by header stamp as live (`processing`: a trigger takes the newest
//! nominal stamped at or before it); outputs are written at the trigger's log time, with the
//! trigger's header stamp as live.

use metrocell_bagtools::{BagSource, ReplayOutput};
use metrocell_msgs::geometry_msgs::msg::PointStamped;
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit};
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_node::{OfflineNode, ReplayArgs};
use metrocell_probe_node::processing::ProbeProcessor;

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let mut processor = ProbeProcessor::from_parameters(node.parameters())?;
    let trigger_topic = node.resolve_topic("probe/trigger")?;
    let nominal_topic = node.resolve_topic("probe/nominal")?;
    let mut source = BagSource::open(&args.bag)?;
    if !source.subscribe::<JointState>(&trigger_topic)? {
        node.logger()
            .warn(source.missing_topic_hint(&trigger_topic));
    }
    // nominals are optional: without them, hits are published but no measured points
    source.subscribe::<PointStamped>(&nominal_topic)?;
    let hits_topic = node.resolve_topic("probe/hits")?;
    let points_topic = node.resolve_topic("measured_points")?;
    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<ProbeHit>(&hits_topic)?;
    output.advertise::<MeasuredPoint>(&points_topic)?;

    let mut rejected = 0u64;
    // SIGINT/SIGTERM stop it between messages, and the output below is still finished
    let stopped = source.replay::<Box<dyn std::error::Error>>(
        || node.interrupted(),
        |m| {
            if m.topic == nominal_topic {
                match m.decode() {
                    Ok(nominal) => processor.nominal(nominal),
                    Err(e) => node.logger().warn(format!("skipped: {e}")),
                }
                return Ok(());
            }
            // A malformed message is reported and skipped, like a trigger the processor rejects.
            let trigger = match m.decode::<JointState>() {
                Ok(trigger) => trigger,
                Err(e) => {
                    rejected += 1;
                    node.logger().warn(format!("skipped: {e}"));
                    return Ok(());
                }
            };
            match processor.trigger(&trigger) {
                Ok((hit, point)) => {
                    output.write(&hits_topic, &hit, m.log_time_ns)?;
                    if let Some(p) = point {
                        output.write(&points_topic, &p, m.log_time_ns)?;
                    }
                }
                Err(e) => {
                    rejected += 1;
                    node.logger()
                        .warn(format!("{e} (log time {} ns)", m.log_time_ns));
                }
            }
            Ok(())
        },
    )?;
    output.finish()?;
    node.logger().info(format!(
        "replayed {} triggers from {}: {rejected} rejected",
        processor.count() + rejected,
        args.bag.display()
    ));
    Ok(node.finish_replay(stopped)?)
}
