//! Publishes `/measured_points` (metrocell_msgs/MeasuredPoint) whose error drifts at known
//! rates, for the dashboard tests: one point per `step` seconds of stamp time (default 60 s),
//! `rate_hz` points per wall second, from 2026-01-01T00:00:00Z.
//! Error [m] at stamp hour h: x = 2 µm + 36 µm/h · h ± 0.5 µm (alternating), y = −3 µm, z = 0,
//! so the dashboard must find an x drift of 36 µm/h and a y drift of 0 (`system_tests::points_ramp`,
//! which the tests read the truth from).
//!
//!   points_ramp_peer --ros-args -p rate_hz:=10.0 -p step:=60.0

use std::time::Duration;

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_node::{qos, MetrocellNode, ParamDecl};
use system_tests::points_ramp;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args(
        "points_ramp_peer",
        vec![
            ParamDecl::new("rate_hz", 10.0, "points per wall-clock second").with_range(0.1, 1000.0),
            ParamDecl::new(
                "step",
                points_ramp::DEFAULT_STEP,
                "stamp seconds between points",
            )
            .with_range(0.001, 86400.0),
        ],
    )?;
    let publisher = node.publisher::<MeasuredPoint>("measured_points", qos::reliable())?;
    let period = Duration::from_secs_f64(1.0 / node.param::<f64>("rate_hz")?);
    let step = node.param::<f64>("step")?;
    let token = node.shutdown_token();
    let mut k: i64 = 0;
    while !token.wait_timeout(period) {
        let mut p = MeasuredPoint {
            point_id: format!("p{k}"),
            source: MeasuredPoint::SOURCE_SIMULATION.into(),
            ..Default::default()
        };
        p.header.stamp = Time::from_nanos(points_ramp::stamp_ns(k, step));
        p.header.frame_id = "machine".into();
        [p.nominal.x, p.nominal.y, p.nominal.z] = points_ramp::nominal(k);
        [p.measured.x, p.measured.y, p.measured.z] = points_ramp::measured(k, step);
        let variance = points_ramp::VARIANCE;
        p.covariance = [variance, 0.0, 0.0, 0.0, variance, 0.0, 0.0, 0.0, variance];
        if publisher.publish(p).is_ok() {
            k += 1;
        }
    }
    Ok(())
}
