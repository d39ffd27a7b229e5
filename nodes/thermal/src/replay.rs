//! The node on a bag (`--bag FILE`): no DDS. Inputs are read in log-time order and each is
//! processed at its log time, which is also the node's clock (staleness, model period), so the
//! numbers equal those of the live node fed by `metrocell bag play`. Outputs are stamped with
//! the log time of the input that caused them.

use metrocell_bagtools::{BagSource, ReplayOutput};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_node::{OfflineNode, ReplayArgs};

use crate::parameters;
use crate::thermal_state::ThermalState;

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let compensator = parameters::compensator(node.parameters())?;
    node.logger().info(parameters::describe(&compensator));
    let mut state = ThermalState::new(compensator, node.param::<f64>("publish_period")?, node.param::<f64>("stale_after")?);

    let mut source = BagSource::open(&args.bag)?;
    let mut sensor_of_topic = Vec::new();
    for s in state.compensator.sensors() {
        let topic = node.resolve_topic(&format!("temperature/{}", s.name))?;
        if !source.subscribe::<Temperature>(&topic)? {
            node.logger().warn(source.missing_topic_hint(&topic));
        }
        sensor_of_topic.push((topic, s.name.clone()));
    }
    let points_topic = node.resolve_topic("measured_points")?;
    if !source.subscribe::<MeasuredPoint>(&points_topic)? {
        node.logger().warn(source.missing_topic_hint(&points_topic));
    }
    let compensated_topic = node.resolve_topic("measured_points/thermal_compensated")?;
    let model_topic = node.resolve_topic("thermal/error_model")?;

    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<MeasuredPoint>(&compensated_topic)?;
    output.advertise::<ErrorModel>(&model_topic)?;

    let (mut inputs, mut compensated, mut not_compensated) = (0u64, 0u64, 0u64);
    // SIGINT/SIGTERM stop it between messages, and the output below is still finished
    let stopped = source.replay::<Box<dyn std::error::Error>>(|| node.interrupted(), |m| {
        inputs += 1;
        let now = m.log_time_ns as i64;
        if m.topic == points_topic {
            // A malformed message is reported and skipped; the replay goes on.
            let point = match m.decode::<MeasuredPoint>() {
                Ok(point) => point,
                Err(e) => {
                    node.logger().warn(format!("skipped: {e}"));
                    not_compensated += 1;
                    return Ok(());
                }
            };
            match state.compensate(&point, now) {
                Ok(out) => {
                    output.write(&compensated_topic, &out, m.log_time_ns)?;
                    compensated += 1;
                }
                Err(e) => {
                    node.logger().warn(format!("{} at log time {} ns: {e}", m.topic, m.log_time_ns));
                    not_compensated += 1;
                }
            }
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
        match state.model_if_due(now) {
            Some(Ok(model)) => output.write(&model_topic, &model, m.log_time_ns)?,
            Some(Err(e)) => node.logger().debug(format!("error model at {now} ns: {e}")),
            None => {}
        }
        Ok(())
    })?;
    output.finish()?;
    node.logger().info(format!(
        "replayed {inputs} messages from {}: {compensated} points compensated, {not_compensated} not",
        args.bag.display()
    ));
    Ok(node.finish_replay(stopped)?)
}
