//! The node on live DDS: subscriptions in, publishers out, node clock as time.

use std::time::Duration;

use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_node::{qos, MetrocellNode, NodeError};

use crate::parameters;
use crate::thermal_state::ThermalState;

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let compensator = parameters::compensator(node.parameters())?;
    node.info(parameters::describe(&compensator));
    let mut state = ThermalState::new(compensator, node.param::<f64>("publish_period")?, node.param::<f64>("stale_after")?);

    let temperature_subs = state
        .compensator
        .sensors()
        .iter()
        .map(|s| Ok((s.name.clone(), node.subscription::<Temperature>(&format!("temperature/{}", s.name), qos::sensor_data())?)))
        .collect::<Result<Vec<_>, NodeError>>()?;
    let points = node.subscription::<MeasuredPoint>("measured_points", qos::reliable())?;
    let compensated = node.publisher::<MeasuredPoint>("measured_points/thermal_compensated", qos::reliable())?;
    let model_pub = node.publisher::<ErrorModel>("thermal/error_model", qos::latched())?;

    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    while !token.is_triggered() {
        for (name, sub) in &temperature_subs {
            while let Ok(Some((t, _))) = sub.take() {
                match state.temperature(name, &t, node.now().to_nanos()) {
                    Ok(()) => diagnostics.set_value(&format!("temperature/{name}"), format!("{:.3} °C", t.temperature)),
                    Err(e) => {
                        node.warn(e);
                        diagnostics.add_count("rejected_readings", 1);
                    }
                }
            }
        }
        while let Ok(Some((p, _))) = points.take() {
            match state.compensate(&p, node.now().to_nanos()) {
                Ok(out) => {
                    if compensated.publish(out).is_ok() {
                        diagnostics.add_count("points_compensated", 1);
                    }
                }
                Err(e) => {
                    diagnostics.warn(e.to_string());
                    diagnostics.add_count("points_not_compensated", 1);
                }
            }
        }
        match state.model_if_due(node.now().to_nanos()) {
            Some(Ok(model)) => {
                let _ = model_pub.publish(model);
                diagnostics.ok("compensating");
            }
            Some(Err(e)) => diagnostics.warn(e.to_string()),
            None => {}
        }
        token.wait_timeout(Duration::from_millis(2));
    }
    Ok(())
}
