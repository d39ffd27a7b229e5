//! The node on a bag (`--bag FILE`): no DDS. Inputs in log-time order; the state orders points
//! by stamp and waits for their signals exactly as live, so the outputs equal the live node's.
//! Outputs are stamped with the log time of the input that caused them.

use metrocell_bagtools::{BagSource, ReplayOutput};
use metrocell_estimator_node::estimator_state::Outputs;
use metrocell_estimator_node::model_message::{alarm_message, observability_message};
use metrocell_estimator_node::parameters;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_node::{OfflineNode, ReplayArgs};

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let model = parameters::model(node.parameters(), &node.resolve_topic("measured_points")?)?;
    let mut source = BagSource::open(&args.bag)?;
    let topics: Vec<(String, String)> = source
        .topics()
        .iter()
        .map(|t| (t.name.clone(), t.type_name.clone()))
        .collect();
    let forward = model.forward_model()?;
    let (mut state, log) = parameters::estimator(node.parameters(), &model, &forward, &topics)?;
    for line in log {
        node.logger().info(line);
    }
    let state_file = node.param::<String>("state_file")?;
    for topic in state.topics() {
        source.subscribe_any(&topic);
    }
    let model_topic = node.resolve_topic("estimator/error_model")?;
    let predicted_topic = node.resolve_topic("estimator/predicted_error")?;
    let diagnostics_topic = node.resolve_topic("/diagnostics")?;
    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<ErrorModel>(&model_topic)?;
    output.advertise::<MeasuredPoint>(&predicted_topic)?;
    output.advertise::<DiagnosticArray>(&diagnostics_topic)?;
    let fqn = node.fully_qualified_name();

    let (mut inputs_read, mut malformed) = (0u64, 0u64);
    let stopped = source.replay::<Box<dyn std::error::Error>>(
        || node.interrupted(),
        |m| {
            inputs_read += 1;
            if let Err(e) = state.message(&m) {
                node.logger().warn(format!("skipped: {e}"));
                malformed += 1;
            }
            for out in state.process() {
                let Outputs {
                    model,
                    predicted,
                    alarm,
                    problem,
                    observability,
                } = out;
                if let Some(problem) = problem {
                    node.logger().debug(problem);
                }
                if let Some(note) = &observability {
                    let message = observability_message(note, &fqn);
                    match &note.text {
                        Some(_) => node.logger().warn(&message.status[0].message),
                        None => node.logger().info(&message.status[0].message),
                    }
                    output.write(&diagnostics_topic, &message, m.log_time_ns)?;
                }
                if let Some(a) = &alarm {
                    let message = alarm_message(a, &fqn);
                    node.logger().warn(&message.status[0].message);
                    output.write(&diagnostics_topic, &message, m.log_time_ns)?;
                }
                if let Some(model) = model {
                    if !state_file.is_empty() {
                        state
                            .saved_state(model.header.stamp.nanos())
                            .save(std::path::Path::new(&state_file))?;
                    }
                    output.write(&model_topic, &model, m.log_time_ns)?;
                }
                for p in predicted {
                    output.write(&predicted_topic, &p, m.log_time_ns)?;
                }
            }
            Ok(())
        },
    )?;
    output.finish()?;
    if let Some(text) = state.observability_now(0).text {
        node.logger().warn(format!("at the end: {text}"));
    }
    node.logger().info(format!(
        "replayed {inputs_read} messages from {}: {}; {} points still waiting for signals at the end, {malformed} malformed messages skipped",
        args.bag.display(),
        state.counters.summary(),
        state.pending()
    ));
    Ok(node.finish_replay(stopped)?)
}
