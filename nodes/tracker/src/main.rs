//! `metrocell-tracker`: laser-tracker logging.
//!
//! Readings come from one backend (parameter `backend`):
//!   * `topic`: `tracker/measurements` (metrocell_msgs/TrackerMeasurement, what the twin and any
//!     other driver publish);
//!   * `tcp`: an instrument streaming ASCII lines `t_s,target,range_m,azimuth_rad,elevation_rad[,T_degC,p_Pa,RH_0_1]`
//!     at `tcp_address` (reconnects with back-off; repeats, garbage and bad values counted);
//!     with `instrument:=total_station_gsi`, a total station's Leica GSI blocks instead, each
//!     published at once on `tracker/measurements` (azimuth = −Hz, elevation = 100 gon − V);
//!   * `--bag IN`: a recorded bag, or a CSV export (`IN` ending in `.csv`) imported through the
//!     `bag import` layout and the mapping file in parameter `csv_mapping`.
//!
//! Each reading is re-corrected for the air (Edlén; the reading's station air, the
//! `weather/{temperature,pressure,humidity}` topics, or configured values), given its covariance (σ angle; σ range
//! a + b·range), grouped into dwells (consecutive readings of one target), averaged with its
//! standard error and tested for turbulence (χ² of the range scatter). The warm-up nest's dwells
//! feed a fit of A + B(1 − e^(−t/τ)). The first `registration_points` targets register the
//! tracker in the machine frame (nominals = `machine/commanded_joint_states` at the dwell's mid
//! time + `tool_offset`; without them, the program's timing T_v = L_T/F + T_s(n − 1) from the
//! `program_*` parameters); from then on every dwell is published on `measured_points`.
//!
//! Publishes: `measured_points` (MeasuredPoint, machine frame), `tracker/dwells`
//! (TrackerMeasurement: averaged, STATUS_TURBULENCE / STATUS_WARMING_UP set), `tracker/warmup`
//! (ErrorModel: A, B, τ with covariance), `/tf_static` (machine → tracker) and `tracker/pose`
//! (PoseWithCovarianceStamped), both transient local; `/diagnostics` counters and warm-up state.
//! When the tracker was moved, re-register its pose (fitted again from the next
//! `registration_points` targets, then published again on `/tf_static` and `tracker/pose`):
//! `ros2 param set /tracker reregister true` (the node resets the parameter to false once it has
//! acted; any client of the node's `set_parameters` service can do it), or a message on
//! `tracker/reregister` (std_msgs/String, any text, logged as the reason). `/diagnostics` counts
//! `reregistrations`.
//!
//!   metrocell-tracker --ros-args -p warmup_target:=nest -p tool_offset:="[0.0, 0.0, -0.15]"
//!   metrocell-tracker --ros-args -p backend:=tcp -p tcp_address:=192.168.0.20:5000
//!   metrocell-tracker --bag SHIFT_BAG --output OUT_BAG --ros-args -p ...

mod live;
mod replay;

use metrocell_node::{MetrocellNode, ParamDecl, ReplayArgs};
use metrocell_tracker_node::parameters;

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-tracker: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut decls = parameters::declarations();
    decls.push(ParamDecl::new("csv_mapping", String::new(), "mapping file (YAML, `metrocell bag import` format) for --bag FILE.csv; empty = the file uses the layout's column names"));
    let (builder, rest) = MetrocellNode::builder("tracker")
        .params(decls)
        .node_argument(ReplayArgs::FLAG, "run on a recorded bag, or on a CSV export (IN_BAG ending in .csv, imported with parameter csv_mapping), instead of DDS; outputs go to OUT_BAG, or to stdout as JSON lines")
        .args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay::run(builder.build_offline()?, &args),
        None => live::run(builder.build()?),
    }
}
