//! Publishes `/measured_points` (metrocell_msgs/MeasuredPoint) whose error drifts at known
//! rates, for the dashboard tests: one point per `step` seconds of stamp time (default 60 s),
//! `rate_hz` points per wall second, from 2026-01-01T00:00:00Z.
//! Error [m] at stamp hour h: x = 2 µm + 36 µm/h · h ± 0.5 µm (alternating), y = −3 µm, z = 0,
//! so the dashboard must find an x drift of 36 µm/h and a y drift of 0.
//!
//!   points_ramp_peer --ros-args -p rate_hz:=10.0 -p step:=60.0

use std::time::Duration;

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_node::{qos, MetrocellNode, ParamDecl};

/// 2026-01-01T00:00:00Z.
const START_NS: i64 = 1_767_225_600_000_000_000;
pub const X_RATE_UM_PER_H: f64 = 36.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args(
        "points_ramp_peer",
        vec![
            ParamDecl::new("rate_hz", 10.0, "points per wall-clock second").with_range(0.1, 1000.0),
            ParamDecl::new("step", 60.0, "stamp seconds between points").with_range(0.001, 86400.0),
        ],
    )?;
    let publisher = node.publisher::<MeasuredPoint>("measured_points", qos::reliable())?;
    let period = Duration::from_secs_f64(1.0 / node.param::<f64>("rate_hz")?);
    let step = node.param::<f64>("step")?;
    let token = node.shutdown_token();
    let mut k: i64 = 0;
    while !token.wait_timeout(period) {
        let t = step * k as f64;
        let h = t / 3600.0;
        let noise = if k % 2 == 0 { 0.5e-6 } else { -0.5e-6 };
        let mut p = MeasuredPoint {
            point_id: format!("p{k}"),
            source: MeasuredPoint::SOURCE_SIMULATION.into(),
            ..Default::default()
        };
        p.header.stamp = Time::from_nanos(START_NS + (t * 1e9).round() as i64);
        p.header.frame_id = "machine".into();
        (p.nominal.x, p.nominal.y, p.nominal.z) = (0.1 + 0.05 * (k % 8) as f64, 0.2, 0.1);
        (p.measured.x, p.measured.y, p.measured.z) = (
            p.nominal.x + 2e-6 + X_RATE_UM_PER_H * 1e-6 * h + noise,
            p.nominal.y - 3e-6,
            p.nominal.z,
        );
        p.covariance = [0.25e-12, 0.0, 0.0, 0.0, 0.25e-12, 0.0, 0.0, 0.0, 0.25e-12];
        if publisher.publish(p).is_ok() {
            k += 1;
        }
    }
    Ok(())
}
