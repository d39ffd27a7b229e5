//! The node on a bag (`--bag FILE`): no DDS. Inputs are read in log-time order and each is
//! processed at its log time, which is also the node's clock (staleness, model period), so the
//! numbers equal those of the live node fed by `metrocell bag play`. Outputs are stamped with
//! the log time of the input that caused them.

use metrocell_bagtools::{BagSource, ReplayOutput};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_node::{OfflineNode, ReplayArgs};

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let mut state = crate::start(node.parameters(), &|line| node.logger().info(line))?;

    let mut source = BagSource::open(&args.bag)?;
    let mut sensor_of_topic = Vec::new();
    for name in state.compensator.sensor_names() {
        let topic = node.resolve_topic(&format!("temperature/{name}"))?;
        if !source.subscribe::<Temperature>(&topic)? {
            node.logger().warn(source.missing_topic_hint(&topic));
        }
        sensor_of_topic.push((topic, name));
    }
    let points_topic = node.resolve_topic("measured_points")?;
    if !source.subscribe::<MeasuredPoint>(&points_topic)? {
        node.logger().warn(source.missing_topic_hint(&points_topic));
    }
    let compensated_topic = node.resolve_topic("measured_points/thermal_compensated")?;
    let model_topic = node.resolve_topic("thermal/error_model")?;
    let drift_topic = node.resolve_topic("thermal/predicted_drift")?;

    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<MeasuredPoint>(&compensated_topic)?;
    output.advertise::<ErrorModel>(&model_topic)?;
    output.advertise::<MeasuredPoint>(&drift_topic)?;

    let (mut inputs, mut malformed) = (0u64, 0u64);
    // SIGINT/SIGTERM stop it between messages, and the output below is still finished
    let stopped = source.replay::<Box<dyn std::error::Error>>(
        || node.interrupted(),
        |m| {
            inputs += 1;
            let now = m.log_time_ns as i64;
            if m.topic == points_topic {
                // A malformed message is reported and skipped; the replay goes on.
                let point = match m.decode::<MeasuredPoint>() {
                    Ok(point) => point,
                    Err(e) => {
                        node.logger().warn(format!("skipped: {e}"));
                        malformed += 1;
                        return Ok(());
                    }
                };
                match state.compensate(&point, now) {
                    Ok(out) => output.write(&compensated_topic, &out, m.log_time_ns)?,
                    Err(e) => node
                        .logger()
                        .warn(format!("{} at log time {} ns: {e}", m.topic, m.log_time_ns)),
                }
                crate::log_fits(&mut state, &point, &|l| node.logger().info(l), &|l| {
                    node.logger().debug(l)
                });
            } else if let Some((_, sensor)) = sensor_of_topic.iter().find(|(t, _)| *t == m.topic) {
                match m.decode::<Temperature>() {
                    Ok(t) => {
                        if let Err(e) = state.temperature(sensor, &t, now) {
                            node.logger().warn(e);
                        }
                    }
                    Err(e) => node.logger().warn(format!("skipped: {e}")),
                }
            }
            if let Some((model, drift)) = state.model_if_due(now) {
                match model {
                    Ok(model) => output.write(&model_topic, &model, m.log_time_ns)?,
                    Err(e) => node.logger().debug(format!("error model at {now} ns: {e}")),
                }
                if let Ok(d) = drift {
                    output.write(&drift_topic, &d, m.log_time_ns)?;
                }
            }
            Ok(())
        },
    )?;
    output.finish()?;
    node.logger().info(format!(
        "replayed {inputs} messages from {}: {}, {malformed} malformed point messages skipped",
        args.bag.display(),
        state.counters.summary()
    ));
    Ok(node.finish_replay(stopped)?)
}
