//! `metrocell-probe`: touch-probe triggers → compensated measured points.
//!
//! Subscribes `probe/trigger` (sensor_msgs/JointState: the axis positions latched at the trigger
//! [m], header.stamp = trigger time; `velocity`, when present, gives the approach direction) and
//! `probe/nominal` (geometry_msgs/PointStamped: the nominal surface point of the next hit, optional).
//! Publishes `probe/hits` (metrocell_msgs/ProbeHit) for every trigger and `measured_points`
//! (metrocell_msgs/MeasuredPoint, source "probe") for triggers with a nominal.
//! Compensation: see `metrocell_probe_node::compensation`; per-message work: `processing`.
//!
//!   metrocell-probe --ros-args -p stylus_radius:=0.0015 -p pretravel:="[10e-6, 0.0, 0.0, 4e-6]"
//!
//! Offline replay (no DDS; inputs in log-time order; outputs to OUT_BAG at the trigger's log
//! time, or as JSON lines on stdout without `--output`):
//!
//!   metrocell-probe --bag IN_BAG [--output OUT_BAG] --ros-args -p ...

mod live;
mod replay;

use metrocell_node::{MetrocellNode, ReplayArgs};
use metrocell_probe_node::processing::declarations;

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-probe: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (builder, rest) = MetrocellNode::builder("probe")
        .params(declarations())
        .node_argument(ReplayArgs::FLAG, ReplayArgs::HELP)
        .args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay::run(builder.build_offline()?, &args),
        None => live::run(builder.build()?),
    }
}
