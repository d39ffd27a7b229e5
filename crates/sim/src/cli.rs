//! `metrocell sim`: [`SimArgs`] (a `clap::Args` the CLI flattens into its subcommand) and
//! [`run_sim_command`].

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use metrocell_bag::ChunkCompression;

use crate::bag::{write_bag, BagOptions, DEFAULT_BAG_CLOCK_RATE};
use crate::cell_options::{load_cell, parse_ground_tilt, run_duration};
use crate::duration_text::parse_duration;
use crate::error::SimError;
use crate::sim_time::{parse_start_time, DEFAULT_START_TIME};

/// Chunk compression of the bag.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Compression {
    Zstd,
    Lz4,
    None,
}

impl From<Compression> for ChunkCompression {
    fn from(c: Compression) -> ChunkCompression {
        match c {
            Compression::Zstd => ChunkCompression::Zstd,
            Compression::Lz4 => ChunkCompression::Lz4,
            Compression::None => ChunkCompression::None,
        }
    }
}

const AFTER_HELP: &str = "\
Topics written (only those whose sensor is in the cell):
  /clock                            rosgraph_msgs/Clock (10 per simulated second)
  /machine/joint_states             sensor_msgs/JointState, actual axis positions (m)
  /machine/commanded_joint_states   sensor_msgs/JointState, commanded axis positions (m) and velocities (m/s)
  /machine/load                     geometry_msgs/WrenchStamped, the load force (N), once, latched
  /temperature/<sensor>             sensor_msgs/Temperature, one per thermocouple (degC)
  /tracker/measurements             metrocell_msgs/TrackerMeasurement (beam breaks flagged, NaN point)
  /tracker/power_on                 sensor_msgs/TimeReference, when the tracker was powered on, once, latched
  /probe/hits                       metrocell_msgs/ProbeHit
  /camera/camera_info               sensor_msgs/CameraInfo (and the rendered frame on /camera/image_raw)
A stationing program (program.stationing: an arm measured by a levelled instrument from several
setups) writes `metrocell bag import`'s layout instead, one row per waypoint, so `calibrate` and
`diagnose` read it as they read an imported recording:
  /measured_points                  metrocell_msgs/MeasuredPoint, the fit points (frame_id total_station@<setup>)
  /check_points                     metrocell_msgs/MeasuredPoint, the check points (kept out of every fit)
  /imu/<sensor>                     sensor_msgs/Imu, each accelerometer's specific force in its frame (m/s^2)
  /machine/commanded_joint_states   and /machine/joint_states, /temperature/<sensor>, at each waypoint

The same cell, duration, seed, ground tilt and start time always give byte-identical bags.

Examples:
  # a three-minute demo bag
  metrocell sim --cell crates/twin/examples/cells/quick_demo.yaml --duration 3min -o bags/quick_demo

  # the 8-hour shift, another noise realisation, stamped on a chosen day
  metrocell sim --cell crates/twin/examples/cells/xfyz_shift.yaml --duration 8h --seed 7 \\
      --start-time 2026-03-02T06:00:00+01:00 -o /tmp/shift_seed7

  # then look at it
  metrocell bag info /tmp/shift_seed7

  # point measurements only (camera_info without rendered frames: kilobytes, not gigabytes)
  metrocell sim --cell crates/twin/examples/cells/xfyz_shift.yaml --duration 8h --no-camera-frames -o /tmp/shift_points

  # a stationing recording of the mobile manipulator on flat ground, then on a seesaw (15 mrad nose
  # down: pitch about the base's y), another noise seed; the program's one pass is the duration
  metrocell sim --cell launch-configs/cells/mobile_manipulator.yaml -o /tmp/flat
  metrocell sim --cell launch-configs/cells/mobile_manipulator.yaml --ground-tilt 0,15mrad --seed 2 -o /tmp/seesaw";

/// Simulate a cell description and record what its sensors would publish as a rosbag2 (MCAP) bag.
#[derive(Debug, Clone, Args)]
#[command(after_help = AFTER_HELP)]
pub struct SimArgs {
    /// Cell description file (YAML), e.g. crates/twin/examples/cells/xfyz_shift.yaml
    #[arg(long, value_name = "FILE")]
    pub cell: PathBuf,
    /// Simulated duration: 8h, 90min, 30s, 1h30min, or seconds (required, except for a
    /// stationing program: its one pass by default)
    #[arg(long, value_name = "D", value_parser = parse_duration_arg)]
    pub duration: Option<f64>,
    /// The ground's tilt under a stationing program's robot, ROLL,PITCH (rad, or with a unit:
    /// 0,15mrad; 2mrad,-1mrad): the base turned by Rx(roll)·Ry(pitch) from level. Replaces the
    /// cell's environment.ground_tilt for this recording
    #[arg(long, value_name = "ROLL,PITCH", allow_hyphen_values = true)]
    pub ground_tilt: Option<String>,
    /// Seed of every noise source (same seed, same bag)
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Bag directory to create (must not already hold a bag)
    #[arg(short = 'o', long = "output", value_name = "BAG_DIR")]
    pub output: PathBuf,
    /// Start of simulated time (RFC 3339), stamped on the first message
    #[arg(long, value_name = "RFC3339", default_value = DEFAULT_START_TIME)]
    pub start_time: String,
    /// Chunk compression of the MCAP file
    #[arg(long, value_enum, default_value_t = Compression::Zstd)]
    pub compression: Compression,
    /// /clock messages per simulated second (0 leaves /clock out)
    #[arg(long, value_name = "HZ", default_value_t = DEFAULT_BAG_CLOCK_RATE)]
    pub clock_rate: f64,
    /// Do not draw a progress bar
    #[arg(long)]
    pub quiet: bool,
    /// Record camera_info only, without rendering camera frames (a point-measurement bag)
    #[arg(long)]
    pub no_camera_frames: bool,
}

fn parse_duration_arg(s: &str) -> Result<f64, String> {
    parse_duration(s).map_err(|e| e.to_string())
}

/// Run `metrocell sim`; returns the process exit code (0 success, 1 failure with the error on
/// stderr, 2 bad arguments).
pub fn run_sim_command(args: SimArgs) -> i32 {
    match run_sim(&args) {
        Ok(()) => 0,
        Err(e @ SimError::InvalidArgument { .. }) => {
            eprintln!("metrocell sim: {e}");
            2
        }
        Err(e) => {
            eprintln!("metrocell sim: {e}");
            1
        }
    }
}

/// `metrocell sim` itself: the bag, or the error that `run_sim_command` prints.
pub fn run_sim(args: &SimArgs) -> Result<(), SimError> {
    let start_ns = parse_start_time(&args.start_time)?;
    if !(args.clock_rate >= 0.0 && args.clock_rate.is_finite()) {
        return Err(SimError::invalid(
            "--clock-rate",
            format!("must be >= 0 and finite, got {}", args.clock_rate),
        ));
    }
    let tilt = args
        .ground_tilt
        .as_deref()
        .map(parse_ground_tilt)
        .transpose()?;
    let cell = load_cell(&args.cell, tilt)?;
    let duration = run_duration(&cell, args.duration, &args.cell)?;
    let options = BagOptions {
        start_ns,
        compression: args.compression.into(),
        clock_rate: (args.clock_rate > 0.0).then_some(args.clock_rate),
        frames: if args.no_camera_frames {
            None
        } else {
            BagOptions::default().frames
        },
        ..BagOptions::default()
    };
    let bar = if args.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(1000)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent}% {msg} (eta {eta})",
        )
        .expect("the progress template is valid"),
    );
    let wall = Instant::now();
    let summary = write_bag(cell, duration, args.seed, &args.output, &options, |p| {
        bar.set_position((1000.0 * p.t / p.duration).round() as u64);
        bar.set_message(format!(
            "{:.0}/{:.0} s simulated, {} messages",
            p.t, p.duration, p.messages
        ));
    })?;
    bar.finish_and_clear();
    let bytes: u64 = std::fs::read_dir(&summary.dir)
        .map(|d| {
            d.filter_map(|e| e.ok()?.metadata().ok())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0);
    println!(
        "wrote {} ({} messages, {:.1} MiB) in {:.1} s",
        summary.dir.display(),
        summary.total_messages,
        bytes as f64 / (1 << 20) as f64,
        wall.elapsed().as_secs_f64()
    );
    for (topic, n) in &summary.messages_per_topic {
        println!("  {topic:<36} {n:>10}");
    }
    Ok(())
}
