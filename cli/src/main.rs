//! `metrocell`: one command for a metrology cell — start it, inspect it, record it, simulate it.
//!
//! Thin by design: every subcommand parses its arguments and calls a library crate.

/// `println!` for the commands that must outlive their stdout (`demo`, which supervises node
/// processes): a closed stdout drops the line instead of panicking, and the command goes on to
/// stop its nodes and write its bag and report. See `restore_sigpipe` for the other commands.
macro_rules! sayln {
    () => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout());
    }};
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` that drops its text when stdout is closed; see `sayln!`.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

mod align_command;
mod bag;
mod calibrate;
mod compensate;
mod delta;
mod demo;
mod diagnose_command;
mod launch_command;
mod router;
mod security_command;
mod topic;
mod verify;
mod vision;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "metrocell",
    version,
    about = "In-process metrology for robot cells and machine tools, as ROS 2 nodes",
    long_about = "In-process metrology for robot cells and machine tools, as ROS 2 nodes.\n\n\
Nodes talk over DDS with ROS 2 names and types, so `ros2` tools can join; these commands let you start\n\
and inspect a cell without a ROS install. DDS honours ROS_DOMAIN_ID and\n\
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST (or ROS_LOCALHOST_ONLY=1) to keep traffic on this machine.",
    after_help = "Examples:\n  metrocell launch launch-configs/demo.launch.yaml duration:=600 output:=/tmp/cell_bag\n  metrocell topic list\n  metrocell topic echo /tracker/measurements --count 3"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Find a robot-mounted camera's frame in the tool's by pure moves and turns (seed 003): /tf_static, URDF joint, cell pose
    Align(align_command::AlignArgs),
    /// Record, inspect, repair, replay, cut, merge, export and import rosbag2 MCAP bags
    #[command(subcommand)]
    Bag(bag::BagCommand),
    /// Camera tools: calibrate from checkerboard images → ROS camera_info YAML
    #[command(subcommand)]
    Camera(vision::camera_command::CameraCommand),
    /// Fit a model file's declared error terms to recordings; write the fitted model with uncertainties
    Calibrate(calibrate::CalibrateArgs),
    /// Turn a fitted model into what the machine runs: compensated G-code, controller tables
    #[command(subcommand)]
    Compensate(compensate::CompensateCommand),
    /// Find fiducials (ArUco/AprilTag markers, checkerboards) in image files
    Detect(vision::detect::DetectArgs),
    /// Delta printer calibration from a printed target (seed 002): identify the geometry, write M665/M666 and Klipper settings
    #[command(subcommand)]
    Delta(delta::DeltaCommand),
    /// Run the main job on the built-in simulated cell: twin, thermal compensation, recorder
    Demo(demo::DemoArgs),
    /// Find where a recording and a model disagree, name the missing physics, add it, show the held-out fit improve
    Diagnose(diagnose_command::DiagnoseArgs),
    /// Start the nodes of a ROS 2 YAML launch file, each as its own process
    Launch(launch_command::LaunchArgs),
    /// CNC router calibration from a drilled plate (seed 000): fit the planar error field, compensate G-code
    #[command(subcommand)]
    Router(router::RouterCommand),
    /// DDS Security keystores, enclaves and permissions (SROS2 layout), like `ros2 security`
    #[command(subcommand)]
    Security(security_command::SecurityCommand),
    /// Simulate a cell into a bag, faster than real time (the digital twin)
    Sim(metrocell_simulation::SimArgs),
    /// Inspect and publish on topics (list, echo, pub, hz), like `ros2 topic`
    #[command(subcommand)]
    Topic(topic::TopicCommand),
    /// Volumetric verification of a machine tool with a laser tracker (seed 001): plan it, report it (Monte Carlo, length test, budget), hole-plate and probe-tip checks
    #[command(subcommand)]
    Verify(verify::VerifyCommand),
}

/// What a closed stdout does to this process. Rust starts every program with SIGPIPE ignored,
/// so a write to a closed pipe returns EPIPE and `println!` panics on it ("failed printing to
/// stdout", exit status 101, the rest of the command's work undone). A command-line tool in a
/// pipeline (`metrocell bag info run | head -3`, `... | true`) should instead end quietly the
/// Unix way, as `cat` or `grep` do: the default action of SIGPIPE, which each command reaches
/// only after it has written its files (they print last). `launch` and `demo` keep SIGPIPE
/// ignored: they supervise node processes and must stop them and finish the recording however
/// their output is read; they never panic on a closed stdout (launch drops the lines, demo
/// writes through `sayln!`).
fn restore_sigpipe(command: &Command) {
    let supervises = match command {
        Command::Launch(a) => !a.dry_run(),
        Command::Demo(_) => true,
        _ => false,
    };
    if !supervises {
        // SAFETY: setting a signal's disposition to its default installs no handler code.
        let _ = unsafe {
            nix::sys::signal::signal(
                nix::sys::signal::Signal::SIGPIPE,
                nix::sys::signal::SigHandler::SigDfl,
            )
        };
    }
}

fn main() {
    let cli = Cli::parse();
    restore_sigpipe(&cli.command);
    let code = match cli.command {
        Command::Align(args) => align_command::run(args),
        Command::Bag(command) => bag::run(command),
        Command::Camera(command) => vision::camera_command::run(command),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Compensate(command) => compensate::run(command),
        Command::Demo(args) => demo::run(args),
        Command::Diagnose(args) => diagnose_command::run(args),
        Command::Detect(args) => vision::detect::run(args),
        Command::Launch(args) => launch_command::run(args),
        Command::Router(command) => router::run(command),
        Command::Verify(command) => verify::run(command),
        Command::Delta(command) => delta::run(command),
        Command::Security(command) => security_command::run(command),
        Command::Sim(args) => metrocell_simulation::run_sim_command(args),
        Command::Topic(command) => topic::run(command),
    };
    std::process::exit(code);
}
