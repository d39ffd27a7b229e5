//! The node on live DDS. Inputs are taken as they come (raw, as a recorder would store them);
//! the state's record stream orders them by stamp.

use std::time::Duration;

use metrocell_bagtools::SourcedMessage;
use metrocell_estimator_node::estimator_state::Outputs;
use metrocell_estimator_node::model_message::{alarm_message, observability_message};
use metrocell_estimator_node::parameters;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_node::{qos, MetrocellNode};
use metrocell_records::signal_topics::POWER_ON_TOPIC;

/// Every input is read reliably with a deep queue: a lost joint state or reading would change
/// the interpolated signals, and the live estimate would no longer equal the replay's.
fn input_qos() -> metrocell_node::QosProfile {
    qos::stream(qos::reliable())
}

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let model = parameters::model(node.parameters(), &node.resolve_topic("measured_points")?)?;
    // the points, the commanded joints and every signal a term of the model reads
    let forward = model.forward_model()?;
    let topics = metrocell_records::declared_topics(&forward, &model.recording);
    let (mut state, log) = parameters::estimator(node.parameters(), &model, &forward, &topics)?;
    for line in log {
        node.info(line);
    }
    let state_file = node.param::<String>("state_file")?;
    let mut inputs = Vec::new();
    for topic in state.topics() {
        let ty = &topics
            .iter()
            .find(|(n, _)| *n == topic)
            .expect("the state reads only the topics it was given")
            .1;
        // the tracker's power-on time is latched: read latched, so a late start still gets it
        let profile = if topic == POWER_ON_TOPIC {
            qos::latched()
        } else {
            input_qos()
        };
        inputs.push(node.raw_subscription(&topic, ty, profile)?);
    }
    let model_pub = node.publisher::<ErrorModel>("estimator/error_model", qos::latched())?;
    let predicted_pub =
        node.publisher::<MeasuredPoint>("estimator/predicted_error", qos::reliable())?;
    let alarm_pub = node.publisher::<DiagnosticArray>("/diagnostics", qos::reliable())?;
    let fqn = node.fully_qualified_name();

    let diagnostics = node.diagnostics();
    diagnostics.ok("waiting for measured points");
    node.watch_inputs(inputs.iter().map(|sub| sub.topic()))?;
    // what the estimator holds, as last said (the heartbeat keeps saying it)
    let mut held: Option<String> = None;
    let token = node.shutdown_token();
    while !token.is_triggered() {
        for sub in &inputs {
            while let Ok(Some(m)) = sub.take() {
                diagnostics.input_seen(sub.topic());
                let message = SourcedMessage {
                    topic: sub.topic().to_string(),
                    log_time_ns: m.receive_time_ns.max(0) as u64,
                    publish_time_ns: m.source_time_ns.unwrap_or(m.receive_time_ns).max(0) as u64,
                    payload: m.payload,
                };
                if let Err(e) = state.message(&message) {
                    node.warn(&e);
                    diagnostics.warn(&e);
                }
            }
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
                diagnostics.warn(&problem);
                node.logger().debug(problem);
            }
            if let Some(note) = &observability {
                let message = observability_message(note, &fqn);
                let text = &message.status[0].message;
                match &note.text {
                    Some(_) => node.warn(text),
                    None => node.info(text),
                }
                held = note.text.clone().map(|_| text.clone());
                diagnostics.set_value("unobservable", note.unobservable.join(", "));
                diagnostics.set_value("at_bound", note.at_bound.join(", "));
                let _ = alarm_pub.publish(message);
            }
            if let Some(a) = &alarm {
                let message = alarm_message(a, &fqn);
                node.warn(&message.status[0].message);
                diagnostics.error(&message.status[0].message);
                let _ = alarm_pub.publish(message);
            }
            if let Some(m) = model {
                if !state_file.is_empty() {
                    if let Err(e) = state
                        .saved_state(m.header.stamp.nanos())
                        .save(std::path::Path::new(&state_file))
                    {
                        node.warn(format!("state file {state_file}: {e}"));
                    }
                }
                let _ = model_pub.publish(m);
                if alarm.is_none() && diagnostics.level() != metrocell_node::DiagnosticLevel::Error
                {
                    match &held {
                        Some(text) => diagnostics.warn(format!("estimating; {text}")),
                        None => diagnostics.ok("estimating"),
                    }
                }
            }
            for p in predicted {
                let _ = predicted_pub.publish(p);
            }
        }
        let c = &state.counters;
        diagnostics.set_value("points_received", c.points_received);
        diagnostics.set_value("accepted", c.accepted);
        diagnostics.set_value("outliers", c.outliers);
        diagnostics.set_value("alarms", c.alarms);
        diagnostics.set_value("points_waiting_for_signals", state.pending());
        diagnostics.set_value("points_not_used", c.points_not_used.values().sum::<u64>());
        diagnostics.set_value("signal_samples_refused", c.refused_samples);
        diagnostics.set_value(
            "innovation_rms_um",
            format!("{:.3}", state.filter().innovation_rms() * 1e6),
        );
        token.wait_timeout(Duration::from_millis(2));
    }
    if let Some(text) = state.observability_now(0).text {
        node.warn(format!("at the end: {text}"));
    }
    node.info(format!("stopping: {}", state.counters.summary()));
    Ok(())
}
