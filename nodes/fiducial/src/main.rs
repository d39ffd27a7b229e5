//! `metrocell-fiducial`: detects fiducials in camera frames.
//!
//! Subscribes `image` (sensor_msgs/Image: mono8, mono16, rgb8, bgr8, rgba8, bgra8) and `camera_info`
//! (sensor_msgs/CameraInfo); publishes `fiducials` (metrocell_msgs/FiducialDetectionArray, header =
//! the image's: capture stamp and frame_id) and `fiducials/pose` (geometry_msgs/PoseWithCovarianceStamped,
//! one per target with a pose; same header). Poses need camera_info and, for markers, `marker_size`.
//! A bad frame is a warning naming the problem; the node keeps running.
//!
//!   metrocell-fiducial --ros-args -p family:=DICT_4X4_50 -p marker_size:=0.02
//!   metrocell-fiducial --ros-args -p family:=checkerboard -p board_cols:=9 -p board_rows:=6 -p square_size:=0.01
//!   metrocell-fiducial --ros-args -p family:=drilled_holes -p board_cols:=5 -p board_rows:=5
//!
//! Offline replay (no DDS; every frame of the bag in log-time order, none dropped; outputs to
//! OUT_BAG at the frame's log time, or as JSON lines on stdout without `--output`):
//!
//!   metrocell-fiducial --bag IN_BAG [--output OUT_BAG] --ros-args -p ...

mod live;
mod replay;

use metrocell_fiducial_node::processing::declarations;
use metrocell_node::{MetrocellNode, ReplayArgs};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-fiducial: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (builder, rest) = MetrocellNode::builder("fiducial")
        .params(declarations())
        .node_argument(ReplayArgs::FLAG, ReplayArgs::HELP)
        .args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay::run(builder.build_offline()?, &args),
        None => live::run(builder.build()?),
    }
}
