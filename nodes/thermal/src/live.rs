//! The node on live DDS: subscriptions in, publishers out, node clock as time.

use std::time::Duration;

use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_node::{qos, MetrocellNode, NodeError};

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let mut state = crate::start(node.parameters(), &|line| node.info(line))?;

    let temperature_subs = state
        .compensator
        .sensor_names()
        .into_iter()
        .map(|name| {
            let sub = node.subscription::<Temperature>(
                &format!("temperature/{name}"),
                qos::stream(qos::sensor_data()),
            )?;
            Ok((name, sub))
        })
        .collect::<Result<Vec<_>, NodeError>>()?;
    let points =
        node.subscription::<MeasuredPoint>("measured_points", qos::stream(qos::reliable()))?;
    let compensated = node.publisher::<MeasuredPoint>(
        "measured_points/thermal_compensated",
        qos::stream(qos::reliable()),
    )?;
    let model_pub = node.publisher::<ErrorModel>("thermal/error_model", qos::latched())?;
    let drift_pub = node.publisher::<MeasuredPoint>("thermal/predicted_drift", qos::reliable())?;

    let diagnostics = node.diagnostics();
    let points_topic = node.watch_inputs(["measured_points"])?.remove(0);
    let temperature_topics = node.watch_inputs(
        temperature_subs
            .iter()
            .map(|(name, _)| format!("temperature/{name}"))
            .collect::<Vec<_>>()
            .iter()
            .map(String::as_str),
    )?;
    let token = node.shutdown_token();
    while !token.is_triggered() {
        for ((name, sub), topic) in temperature_subs.iter().zip(&temperature_topics) {
            while let Ok(Some((t, _))) = sub.take() {
                diagnostics.input_seen(topic);
                match state.temperature(name, &t, node.now().to_nanos()) {
                    Ok(()) => diagnostics.set_value(
                        &format!("temperature/{name}"),
                        format!("{:.3} °C", t.temperature),
                    ),
                    Err(e) => node.warn(e),
                }
            }
        }
        while let Ok(Some((p, _))) = points.take() {
            diagnostics.input_seen(&points_topic);
            match state.compensate(&p, node.now().to_nanos()) {
                Ok(out) => {
                    let _ = compensated.publish(out);
                }
                Err(e) => diagnostics.warn(e.to_string()),
            }
            crate::log_fits(&mut state, &p, &|l| node.info(l), &|l| {
                node.logger().debug(l)
            });
        }
        let now = node.now().to_nanos();
        if let Some((model, drift)) = state.model_if_due(now) {
            match model {
                Ok(model) => {
                    let _ = model_pub.publish(model);
                    diagnostics.ok("compensating");
                }
                Err(e) => diagnostics.warn(e.to_string()),
            }
            if let Ok(d) = drift {
                diagnostics.set_value(
                    "predicted_drift_um",
                    format!(
                        "[{:.2}, {:.2}, {:.2}]",
                        (d.measured.x - d.nominal.x) * 1e6,
                        (d.measured.y - d.nominal.y) * 1e6,
                        (d.measured.z - d.nominal.z) * 1e6
                    ),
                );
                let _ = drift_pub.publish(d);
            }
            let c = &state.counters;
            diagnostics.set_value("points_compensated", c.points_compensated);
            diagnostics.set_value("points_not_compensated", c.not_compensated_total());
            for (reason, n) in &c.points_not_compensated {
                diagnostics.set_value(&format!("points_not_compensated/{reason}"), n);
            }
            diagnostics.set_value("rejected_readings", c.rejected_readings);
            diagnostics.set_value("stale_sensors", state.stale_sensors(now).join(", "));
        }
        token.wait_timeout(Duration::from_millis(2));
    }
    Ok(())
}
