//! `metrocell-estimator`: the machine's error model, estimated online during a shift.
//!
//! Subscribes `measured_points` (metrocell_msgs/MeasuredPoint, machine frame),
//! `machine/commanded_joint_states` (sensor_msgs/JointState) and the topic of every signal a term
//! of the model reads (`temperature/<sensor>`, `/tracker/power_on`, `/machine/load`), turned into
//! measurement records as `metrocell calibrate` does from a bag (crates/records `RecordStream`); keeps a recursive estimator (an extended Kalman filter with
//! random-walk drift for the parameters named in `process_noise`) over the model cell file
//! (`model`); publishes `estimator/error_model` (metrocell_msgs/ErrorModel, latched: every
//! parameter `label.param` with its SI unit and the covariance, each term described),
//! `estimator/predicted_error` (MeasuredPoint per configured joint vector: nominal and predicted
//! true tool point, covariance of the error) and, when the model stops explaining the data
//! (moving normalised-innovation χ² test), an ERROR on `/diagnostics`.
//!
//!   metrocell-estimator --ros-args -p model:=launch-configs/cells/demo_model.yaml \
//!       -p process_noise:="['positioning[z].c0=1e-7']" -p predict_points:="[0.2, 0.15, 0.1]" \
//!       -p state_file:=/var/lib/metrocell/estimator.json
//!
//! Offline replay (no DDS; the same outputs as the live node fed by `metrocell bag play`):
//!
//!   metrocell-estimator --bag SHIFT_BAG [--output OUT_BAG] --ros-args -p model:=...

mod live;
mod replay;

use metrocell_estimator_node::parameters;
use metrocell_node::{MetrocellNode, ReplayArgs};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-estimator: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (builder, rest) = MetrocellNode::builder("estimator")
        .params(parameters::declarations())
        .node_argument(ReplayArgs::FLAG, ReplayArgs::HELP)
        .args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay::run(builder.build_offline()?, &args),
        None => live::run(builder.build()?),
    }
}
