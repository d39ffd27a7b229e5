//! `metrocell-thermal`: thermal drift correction.
//!
//! Subscribes `temperature/<sensor>` (sensor_msgs/Temperature) for every configured sensor and
//! `measured_points` (metrocell_msgs/MeasuredPoint); publishes `measured_points/thermal_compensated`
//! with the axis-scale growth α·q·(T(q) − T_ref) removed and the covariance enlarged, and a
//! latched `thermal/error_model` (metrocell_msgs/ErrorModel) with each axis's current strain.
//!
//!   metrocell-thermal --ros-args -p sensors:="[x_left, x_right]" -p sensor_axes:="[x, x]" \
//!       -p sensor_positions:="[0.0, 0.8]" -p alpha:=11.5e-6
//!
//! Offline replay (no DDS; inputs from the bag in log-time order, as fast as the CPU allows;
//! outputs to OUT_BAG, or as JSON lines on stdout without `--output`):
//!
//!   metrocell-thermal --bag DEMO_BAG [--output OUT_BAG] --ros-args -p ...

mod live;
mod parameters;
mod replay;
mod thermal_state;

use metrocell_node::{MetrocellNode, ReplayArgs};

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
    let (builder, rest) = MetrocellNode::builder("thermal").params(parameters::declarations()).node_argument(ReplayArgs::FLAG, ReplayArgs::HELP).args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay::run(builder.build_offline()?, &args),
        None => live::run(builder.build()?),
    }
}
