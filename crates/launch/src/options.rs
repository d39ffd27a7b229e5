//! How the launcher is configured by its caller (the `metrocell launch` command or a test).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Settings for loading and running a launch file. `LaunchOptions::default()` is what the CLI wants.
#[derive(Clone)]
pub struct LaunchOptions {
    /// After SIGINT has been sent to every child, how long to wait before SIGKILL. Default 2 s.
    pub grace_period: Duration,
    /// Directories searched for a node's `exec`; `None` = [`crate::default_search_path`]
    /// (the running executable's directory, then `PATH`).
    pub executable_search_path: Option<Vec<PathBuf>>,
    /// What `$(find-pkg-share metrocell)` / `$(find-pkg-share metrocell_msgs)` give; `None` =
    /// env `METROCELL_SHARE`, else the nearest directory holding `launch-configs/` found by walking
    /// up from the launch file being read.
    pub share_dir: Option<PathBuf>,
    /// The environment `$(env)`/`$(optenv)` read (and `METROCELL_SHARE`, `AMENT_PREFIX_PATH`);
    /// `None` = the launcher's own environment. Children always inherit the launcher's environment.
    pub environment: Option<BTreeMap<String, String>>,
    /// Install SIGINT/SIGTERM handlers for the duration of the run (the CLI wants this; a test
    /// running the engine in a thread uses `shutdown` instead). A second signal during the grace
    /// period sends SIGKILL at once.
    pub handle_signals: bool,
    /// Request a shutdown from another thread (same effect as Ctrl-C).
    pub shutdown: ShutdownHandle,
    /// Where children's output lines and the launcher's own reports go.
    pub output: OutputSink,
}

impl Default for LaunchOptions {
    fn default() -> Self {
        LaunchOptions {
            grace_period: Duration::from_secs(2),
            executable_search_path: None,
            share_dir: None,
            environment: None,
            handle_signals: true,
            shutdown: ShutdownHandle::default(),
            output: OutputSink::Inherit,
        }
    }
}

impl LaunchOptions {
    /// Looks a variable up in `environment`, or in the process environment.
    pub(crate) fn env_var(&self, name: &str) -> Option<String> {
        match &self.environment {
            Some(map) => map.get(name).cloned(),
            None => std::env::var(name).ok(),
        }
    }
}

/// A cloneable "please stop" flag shared between the launcher and whoever wants it stopped.
#[derive(Clone, Debug, Default)]
pub struct ShutdownHandle(Arc<AtomicBool>);

impl ShutdownHandle {
    pub fn new() -> Self {
        Self::default()
    }
    /// Ask the launcher to stop: SIGINT to every child, SIGKILL after the grace period.
    pub fn request(&self) {
        self.0.store(true, Ordering::SeqCst);
    }
    pub fn is_requested(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// Destination of output lines.
#[derive(Clone, Default)]
pub enum OutputSink {
    /// Children's stdout lines to the launcher's stdout, their stderr lines and the launcher's
    /// reports to the launcher's stderr.
    #[default]
    Inherit,
    /// Everything, line by line, into one writer (tests capture output this way).
    Shared(Arc<Mutex<dyn Write + Send>>),
}

/// Which stream of the launcher a line belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stream {
    Stdout,
    Stderr,
}

impl OutputSink {
    /// Writes one whole line (a `\n` is added), holding the lock so lines never interleave.
    pub(crate) fn write_line(&self, stream: Stream, line: &str) {
        match self {
            OutputSink::Inherit => {
                let result = match stream {
                    Stream::Stdout => writeln!(std::io::stdout().lock(), "{line}"),
                    Stream::Stderr => writeln!(std::io::stderr().lock(), "{line}"),
                };
                // A closed terminal must not take the launcher down; the children still need stopping.
                let _ = result;
            }
            OutputSink::Shared(writer) => {
                let mut w = writer
                    .lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner());
                let _ = writeln!(w, "{line}");
                let _ = w.flush();
            }
        }
    }
}
