//! The result of reading a launch file: the processes to run, fully resolved, and the launch
//! arguments that were declared. Nothing here refers back to YAML.

use std::path::PathBuf;
use std::time::Duration;

/// Everything a launch file asks for, after arguments, substitutions and includes are resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct LaunchPlan {
    /// In the order the launch files declare them (includes expanded in place).
    pub processes: Vec<ProcessSpec>,
    /// Every `arg` met while reading, in order, with the value it resolved to.
    pub arguments: Vec<DeclaredArgument>,
}

/// One process to start (from a `node` or an `executable` action).
#[derive(Clone, Debug, PartialEq)]
pub struct ProcessSpec {
    /// Prefix for its output lines: the node `name`, else the executable's file name; made unique
    /// within a plan by appending `-2`, `-3`, ...
    pub label: String,
    /// The resolved executable.
    pub program: PathBuf,
    /// argv[1..]: the `args` words, then (for nodes) the `--ros-args ...` tail.
    pub args: Vec<String>,
    /// Extra environment variables (`env` list), added to the launcher's environment.
    pub env: Vec<(String, String)>,
    /// Working directory (`cwd` of an `executable`); `None` = the launcher's.
    pub cwd: Option<PathBuf>,
    pub respawn: bool,
    /// Wait between an exit and the restart.
    pub respawn_delay: Duration,
    /// How many restarts at most; `None` = no limit.
    pub respawn_max_retries: Option<u32>,
    pub output: OutputMode,
    /// `file:line` of the action, for messages.
    pub origin: String,
}

/// The `output` attribute. All modes are accepted; the launcher shows every line on its own
/// stdout/stderr with the `[label]` prefix in all of them (there is no separate log file).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputMode {
    Screen,
    Log,
    Both,
}

/// An `arg` declaration and the value it took.
#[derive(Clone, Debug, PartialEq)]
pub struct DeclaredArgument {
    pub name: String,
    pub default: Option<String>,
    pub description: Option<String>,
    pub value: String,
    /// `file:line` of the declaration.
    pub origin: String,
}

impl ProcessSpec {
    /// The full command line, program first, as text (for display and tests).
    pub fn command_line(&self) -> Vec<String> {
        std::iter::once(self.program.display().to_string())
            .chain(self.args.iter().cloned())
            .collect()
    }
}
