//! Engine behind `metrocell launch FILE [name:=value ...]`: reads a ROS 2 YAML launch file
//! (the `launch_yaml` / `launch_ros` frontend format, see [`launch_file`] for the accepted
//! actions and keys), turns every `node` / `executable` into a command line (see
//! [`command_line`]) and runs them under supervision (see [`supervisor`]).
//!
//! ```no_run
//! use metrocell_launch::{parse_launch_arguments, run_launch, LaunchOptions};
//! let args = parse_launch_arguments(&["rate:=10"]).unwrap();
//! let outcome = run_launch("launch-configs/demo.launch.yaml".as_ref(), &args, &LaunchOptions::default())?;
//! std::process::exit(outcome.exit_code());
//! # Ok::<(), metrocell_launch::LaunchError>(())
//! ```
//!
//! Unix only (process groups and signals).

pub mod command_line;
pub mod error;
pub mod launch_file;
pub mod marked_yaml;
pub mod options;
pub mod plan;
mod substitution;
pub mod supervisor;

use std::path::Path;

pub use command_line::default_search_path;
pub use error::LaunchError;
pub use launch_file::{load_launch_plan, parse_launch_arguments};
pub use options::{LaunchOptions, OutputSink, ShutdownHandle};
pub use plan::{DeclaredArgument, LaunchPlan, OutputMode, ProcessSpec};
pub use supervisor::{supervise, ExitKind, LaunchOutcome, ProcessReport};

/// Loads `path` with the command-line launch arguments `args` (pairs from `name:=value`, see
/// [`parse_launch_arguments`]) and runs every process until the launch ends: all processes
/// exited, or Ctrl-C / SIGTERM (when `options.handle_signals`) or `options.shutdown` was
/// requested. Errors in the launch file are returned before anything is started.
pub fn run_launch(
    path: &Path,
    args: &[(String, String)],
    options: &LaunchOptions,
) -> Result<LaunchOutcome, LaunchError> {
    let plan = load_launch_plan(path, args, options)?;
    supervise(&plan, options)
}
