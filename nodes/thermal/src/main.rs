//! `metrocell-thermal`: thermal drift correction.
//!
//! Subscribes `temperature/<sensor>` (sensor_msgs/Temperature) for every configured sensor and
//! `measured_points` (metrocell_msgs/MeasuredPoint); publishes `measured_points/thermal_compensated`
//! with the axis-scale growth α·q·(T(q) − T_ref) removed and the covariance enlarged, and a
//! latched `thermal/error_model` (metrocell_msgs/ErrorModel) with each axis's current strain.
//!
//!   metrocell-thermal --ros-args -p sensors:="[x_left, x_right]" -p sensor_axes:="[x, x]" \
//!       -p sensor_positions:="[0.0, 0.8]" -p alpha:=11.5e-6

mod parameters;

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_node::{qos, MetrocellNode, NodeError};
use nalgebra::{Matrix3, Vector3};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-thermal: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("thermal", parameters::declarations())?;
    let compensator = parameters::compensator(&node)?;
    let period = Duration::from_secs_f64(node.param::<f64>("publish_period")?);
    let stale_after = Duration::from_secs_f64(node.param::<f64>("stale_after")?);
    node.info(format!(
        "alpha={:e} 1/K ± {:e}, T_ref={} °C, sensors: {}",
        compensator.alpha,
        compensator.alpha_uncertainty,
        compensator.reference_temperature,
        compensator.sensors().iter().map(|s| format!("{}@{}{:+.3}m", s.name, ["x", "y", "z"][s.axis], s.position)).collect::<Vec<_>>().join(", ")
    ));

    let temperature_subs = compensator
        .sensors()
        .iter()
        .map(|s| Ok((s.name.clone(), node.subscription::<Temperature>(&format!("temperature/{}", s.name), qos::sensor_data())?)))
        .collect::<Result<Vec<_>, NodeError>>()?;
    let points = node.subscription::<MeasuredPoint>("measured_points", qos::reliable())?;
    let compensated = node.publisher::<MeasuredPoint>("measured_points/thermal_compensated", qos::reliable())?;
    let model_pub = node.publisher::<ErrorModel>("thermal/error_model", qos::latched())?;

    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let mut latest: BTreeMap<String, (f64, f64, Instant)> = BTreeMap::new();
    let mut next_model = Instant::now();
    while !token.is_triggered() {
        for (name, sub) in &temperature_subs {
            while let Ok(Some((t, _))) = sub.take() {
                if t.temperature.is_finite() && t.variance.is_finite() && t.variance >= 0.0 {
                    latest.insert(name.clone(), (t.temperature, t.variance, Instant::now()));
                    diagnostics.set_value(&format!("temperature/{name}"), format!("{:.3} °C", t.temperature));
                } else {
                    node.warn(format!("temperature/{name}: rejected reading {} °C (variance {})", t.temperature, t.variance));
                    diagnostics.add_count("rejected_readings", 1);
                }
            }
        }
        let reading = |name: &str| latest.get(name).filter(|r| r.2.elapsed() <= stale_after).map(|r| (r.0, r.1));

        while let Ok(Some((p, _))) = points.take() {
            let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
            let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
            let cov = Matrix3::from_row_slice(&p.covariance);
            match compensator.compensate(&nominal, &measured, &cov, &reading) {
                Ok((c, c_cov)) => {
                    let mut out = p.clone();
                    (out.measured.x, out.measured.y, out.measured.z) = (c.x, c.y, c.z);
                    out.covariance.copy_from_slice(c_cov.transpose().as_slice());
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

        if Instant::now() >= next_model {
            next_model += period;
            match parameters::error_model(&compensator, &reading, node.now().to_nanos()) {
                Ok(model) => {
                    let _ = model_pub.publish(model);
                    diagnostics.ok("compensating");
                }
                Err(e) => diagnostics.warn(e.to_string()),
            }
        }
        token.wait_timeout(Duration::from_millis(2));
    }
    Ok(())
}
