//! The node on live DDS. Inputs are taken as they come; the state orders them by stamp.

use std::time::Duration;

use metrocell_estimator_node::estimator_state::Outputs;
use metrocell_estimator_node::model_message::alarm_message;
use metrocell_estimator_node::parameters;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::{JointState, Temperature};
use metrocell_node::{qos, MetrocellNode, NodeError};

/// Every input is read reliably with a deep queue: a lost joint state or reading would change
/// the interpolated signals, and the live estimate would no longer equal the replay's.
fn input_qos() -> metrocell_node::QosProfile {
    qos::stream(qos::reliable())
}

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let (mut state, inputs, log) = parameters::estimator(node.parameters())?;
    for line in log {
        node.info(line);
    }
    let state_file = node.param::<String>("state_file")?;
    let points = node.subscription::<MeasuredPoint>("measured_points", input_qos())?;
    let joints = node.subscription::<JointState>("machine/commanded_joint_states", input_qos())?;
    let temperatures = inputs
        .sensors
        .iter()
        .map(|name| Ok((name.clone(), node.subscription::<Temperature>(&format!("temperature/{name}"), input_qos())?)))
        .collect::<Result<Vec<_>, NodeError>>()?;
    let model_pub = node.publisher::<ErrorModel>("estimator/error_model", qos::latched())?;
    let predicted_pub = node.publisher::<MeasuredPoint>("estimator/predicted_error", qos::reliable())?;
    let alarm_pub = node.publisher::<DiagnosticArray>("/diagnostics", qos::reliable())?;
    let fqn = node.fully_qualified_name();

    let diagnostics = node.diagnostics();
    diagnostics.ok("waiting for measured points");
    let token = node.shutdown_token();
    while !token.is_triggered() {
        while let Ok(Some((js, _))) = joints.take() {
            state.joint_state(&js);
        }
        for (name, sub) in &temperatures {
            while let Ok(Some((t, _))) = sub.take() {
                state.temperature(name, &t);
            }
        }
        while let Ok(Some((p, _))) = points.take() {
            state.point(p);
        }
        for out in state.process() {
            let Outputs { model, predicted, alarm, problem } = out;
            if let Some(problem) = problem {
                diagnostics.warn(&problem);
                node.logger().debug(problem);
            }
            if let Some(a) = &alarm {
                let message = alarm_message(a, &fqn);
                node.warn(&message.status[0].message);
                diagnostics.error(&message.status[0].message);
                let _ = alarm_pub.publish(message);
            }
            if let Some(m) = model {
                if !state_file.is_empty() {
                    if let Err(e) = state.saved_state(m.header.stamp.nanos()).save(std::path::Path::new(&state_file)) {
                        node.warn(format!("state file {state_file}: {e}"));
                    }
                }
                let _ = model_pub.publish(m);
                if alarm.is_none() && diagnostics.level() != metrocell_node::DiagnosticLevel::Error {
                    diagnostics.ok("estimating");
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
        diagnostics.set_value("points_with_held_signals", c.points_with_held_signals);
        diagnostics.set_value("joint_states_without_axes", c.joint_states_without_axes);
        diagnostics.set_value("rejected_temperature_readings", c.rejected_readings);
        diagnostics.set_value("innovation_rms_um", format!("{:.3}", state.filter().innovation_rms() * 1e6));
        token.wait_timeout(Duration::from_millis(2));
    }
    node.info(format!("stopping: {}", state.counters.summary()));
    Ok(())
}
