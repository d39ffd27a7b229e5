//! `metrocell-recorder`: records DDS topics into a crash-safe rosbag2 MCAP bag (see the
//! library, `metrocell_recorder_node`, for what is recorded, with which QoS, and how losses are
//! counted; `metrocell bag record` runs the same code in-process).
//!
//! Exit: SIGINT/SIGTERM finish the bag (exit 0). A write failure (disk full) logs the file,
//! stops recording, leaves the bag sealed and valid, exits 1.
//!
//!   metrocell-recorder --ros-args -p output:=run42 -p exclude:="/camera/.*" -p compression:=lz4

use metrocell_node::MetrocellNode;
use metrocell_recorder_node::{parameters, record, RecorderSettings};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-recorder: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("recorder", parameters::declarations())?;
    let settings = RecorderSettings::from_node(&node)?;
    record(&mut node, &settings)?;
    Ok(())
}
