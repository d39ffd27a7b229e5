//! Parameters of `metrocell-sim` and their checked values.

use metrocell_node::{MetrocellNode, ParamDecl};
use metrocell_simulation::cell_options::{load_cell, parse_ground_tilt, run_duration};
use metrocell_simulation::duration_text::parse_duration;
use metrocell_simulation::sim_time::{check_span, parse_start_time, DEFAULT_START_TIME};
use metrocell_simulation::{Pacer, SimError};

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("cell", "", "cell description file (YAML), e.g. crates/twin/examples/cells/quick_demo.yaml"),
        ParamDecl::new("duration", "3min", "simulated duration of one run: 8h, 90min, 30s or seconds; `auto` for a stationing program's one pass"),
        ParamDecl::new("ground_tilt", "", "a stationing program's ground tilt ROLL,PITCH (rad or with a unit, e.g. 0,15mrad), replacing the cell's environment.ground_tilt; empty: the cell's"),
        ParamDecl::new("seed", 1i64, "seed of every noise source").with_range(0.0, 9.007_199_254_740_992e15),
        ParamDecl::new("speed", 1.0, "simulated seconds per wall-clock second").with_range(1e-3, 1e5),
        ParamDecl::new("loop", false, "start over when the run ends (time keeps advancing, same data)"),
        ParamDecl::new("start_time", DEFAULT_START_TIME, "RFC 3339 start of simulated time"),
        ParamDecl::new("clock_rate", 100.0, "/clock messages per wall-clock second").with_range(1.0, 1000.0),
        ParamDecl::new("camera_images", true, "render an image on /camera/image_raw for every camera frame request (render, encode and write: about 0.05 s of CPU per 5 MP frame in a release build, measured in BENCHMARKS.md)"),
        ParamDecl::new("start_delay", 0.0, "wall-clock seconds to wait before the first message, so recorders and other nodes discover the topics first")
            .with_range(0.0, 3600.0),
        ParamDecl::new("wait_for_recorder", 0.0, "before the first message, wait up to this many wall-clock seconds until the node named by recorder_node subscribes to every topic the twin publishes, so the bag gets every message (0: do not wait)")
            .with_range(0.0, 3600.0),
        ParamDecl::new("recorder_node", "recorder", "name of the recorder node wait_for_recorder waits for: bare (any namespace) or fully qualified; metrocell-recorder is 'recorder', metrocell bag record 'recorder' too (--node-name), ros2 bag record 'rosbag2_recorder'. Found by name in ROS 2's ros_discovery_info, so another node reading every topic (the dashboard) is not taken for it"),
    ]
}

/// Checked parameter values.
pub struct Settings {
    pub cell: String,
    /// A stationing program's ground tilt replacing the cell's (roll, pitch; rad).
    pub ground_tilt: Option<[f64; 2]>,
    pub duration: f64,
    pub seed: u64,
    pub pacer: Pacer,
    pub repeat: bool,
    pub start_ns: u64,
    pub clock_period: f64,
    pub camera_images: bool,
}

pub fn settings(node: &MetrocellNode) -> Result<Settings, Box<dyn std::error::Error>> {
    let cell = node.param::<String>("cell")?;
    if cell.trim().is_empty() {
        return Err("parameter cell is empty: give a cell file, e.g. --ros-args -p cell:=crates/twin/examples/cells/quick_demo.yaml".into());
    }
    let tilt = node.param::<String>("ground_tilt")?;
    let ground_tilt = if tilt.trim().is_empty() {
        None
    } else {
        Some(parse_ground_tilt(&tilt)?)
    };
    let duration = match node.param::<String>("duration")?.trim() {
        "auto" => run_duration(
            &load_cell(std::path::Path::new(&cell), ground_tilt)?,
            None,
            std::path::Path::new(&cell),
        )?,
        text => parse_duration(text)?,
    };
    let speed = node.param::<f64>("speed")?;
    let pacer = Pacer::new(speed).ok_or_else(|| SimError::InvalidArgument {
        what: "parameter speed".into(),
        reason: format!("must be > 0, got {speed}"),
    })?;
    let start_ns = parse_start_time(&node.param::<String>("start_time")?)?;
    check_span(start_ns, duration)?;
    Ok(Settings {
        cell,
        ground_tilt,
        duration,
        seed: node.param::<i64>("seed")?.max(0) as u64,
        pacer,
        repeat: node.param::<bool>("loop")?,
        start_ns,
        clock_period: 1.0 / node.param::<f64>("clock_rate")?,
        camera_images: node.param::<bool>("camera_images")?,
    })
}
