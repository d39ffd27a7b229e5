//! Running the processes of a [`LaunchPlan`] and looking after them.
//!
//! * Every process is started in its own process group (so a terminal Ctrl-C reaches only the
//!   launcher, which then stops the children in order, and signals reach a child's own children).
//! * Each line a child writes to stdout/stderr is echoed as `[label] line` on the same stream.
//! * Each exit is reported (`[launch] [label] exited with code N` / `killed by signal SIGX`).
//! * `respawn: true` processes are restarted after `respawn_delay`, at most `respawn_max_retries` times.
//! * Shutdown (Ctrl-C / SIGTERM when `handle_signals`, or [`crate::ShutdownHandle::request`]): SIGINT
//!   to every child's process group, SIGKILL to those still alive after the grace period.
//! * The run ends when every process has ended for good. Once all processes that do not respawn
//!   have exited, respawning ones are stopped as on shutdown (the launch has nothing left to serve).
//!
//! A process "failed" when its final exit (not one caused by the launcher's shutdown) has a
//! non-zero code or was caused by a signal, or when it could not be started.

use std::io::{BufRead, BufReader, Read};
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{channel, RecvTimeoutError, Sender};
use std::sync::{Arc, Condvar, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use nix::sys::signal::{killpg, SigHandler, Signal};
use nix::unistd::Pid;

use crate::error::LaunchError;
use crate::options::{LaunchOptions, OutputSink, Stream};
use crate::plan::{LaunchPlan, ProcessSpec};

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub struct LaunchOutcome {
    /// True when the run ended because a shutdown was requested (signal or handle).
    pub interrupted: bool,
    /// One entry per process of the plan, in plan order.
    pub processes: Vec<ProcessReport>,
}

/// What became of one process.
#[derive(Clone, Debug, PartialEq)]
pub struct ProcessReport {
    pub label: String,
    /// How many times it was started (1 + restarts; 0 if it never started).
    pub starts: u32,
    /// Its last exit.
    pub last_exit: ExitKind,
    /// True when that exit counts as a failure (see the module docs).
    pub failed: bool,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ExitKind {
    Code(i32),
    /// Ended by this signal number.
    Signal(i32),
    /// Could not be started; the reason.
    NotStarted(String),
}

impl LaunchOutcome {
    /// True when no process failed.
    pub fn success(&self) -> bool {
        self.processes.iter().all(|p| !p.failed)
    }

    /// The launcher's exit status: 0 when no process failed (a requested shutdown included), 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        if self.success() {
            0
        } else {
            1
        }
    }
}

/// Number of SIGINT/SIGTERM received since the handlers were installed.
static SIGNALS_RECEIVED: AtomicUsize = AtomicUsize::new(0);

extern "C" fn on_signal(_: nix::libc::c_int) {
    // Only an atomic store: async-signal-safe.
    SIGNALS_RECEIVED.fetch_add(1, Ordering::SeqCst);
}

/// Installed SIGINT/SIGTERM handlers, restored to the previous ones on drop.
struct SignalGuard {
    previous: Vec<(Signal, nix::sys::signal::SigAction)>,
}

impl SignalGuard {
    fn install() -> Result<Self, LaunchError> {
        use nix::sys::signal::{sigaction, SaFlags, SigAction, SigSet};
        SIGNALS_RECEIVED.store(0, Ordering::SeqCst);
        let action = SigAction::new(
            SigHandler::Handler(on_signal),
            SaFlags::SA_RESTART,
            SigSet::empty(),
        );
        let mut previous = Vec::new();
        for sig in [Signal::SIGINT, Signal::SIGTERM] {
            // SAFETY: the handler only touches an atomic, which is async-signal-safe.
            let old = unsafe { sigaction(sig, &action) }
                .map_err(|e| LaunchError::Signals(format!("{sig}: {e}")))?;
            previous.push((sig, old));
        }
        Ok(SignalGuard { previous })
    }
}

impl Drop for SignalGuard {
    fn drop(&mut self) {
        for (sig, old) in &self.previous {
            // SAFETY: restoring the disposition that was in place before `install`.
            let _ = unsafe { nix::sys::signal::sigaction(*sig, old) };
        }
    }
}

/// A running instance reported as ended by its waiter thread.
struct Exited {
    slot: usize,
    status: std::io::Result<ExitStatus>,
}

enum State {
    Running { pid: i32 },
    RespawnAt(Instant),
    Done,
}

struct Slot<'p> {
    spec: &'p ProcessSpec,
    state: State,
    starts: u32,
    last_exit: Option<ExitKind>,
    failed: bool,
}

/// Starts every process of `plan` and supervises them until the run ends (see the module docs).
pub fn supervise(plan: &LaunchPlan, options: &LaunchOptions) -> Result<LaunchOutcome, LaunchError> {
    let _signals = if options.handle_signals {
        Some(SignalGuard::install()?)
    } else {
        None
    };
    let sink = &options.output;
    let (tx, rx) = channel::<Exited>();
    let mut slots: Vec<Slot> = plan
        .processes
        .iter()
        .map(|spec| Slot {
            spec,
            state: State::Done,
            starts: 0,
            last_exit: None,
            failed: false,
        })
        .collect();
    for i in 0..slots.len() {
        start(&mut slots, i, sink, &tx);
    }

    let mut interrupted = false;
    let mut stopping_since: Option<Instant> = None;
    let mut killed = false;
    let mut signals_seen_at_stop = 0;
    let any_non_respawning = plan.processes.iter().any(|p| !p.respawn);
    loop {
        let signals = if options.handle_signals {
            SIGNALS_RECEIVED.load(Ordering::SeqCst)
        } else {
            0
        };
        let requested = signals > 0 || options.shutdown.is_requested();
        if stopping_since.is_none() {
            let only_respawners_left = any_non_respawning
                && slots
                    .iter()
                    .all(|s| s.spec.respawn || matches!(s.state, State::Done))
                && slots.iter().any(|s| !matches!(s.state, State::Done));
            if requested || only_respawners_left {
                interrupted = requested;
                let why = if requested {
                    "shutdown requested"
                } else {
                    "all processes that do not respawn have exited"
                };
                report(
                    sink,
                    &format!("[launch] {why}: sending SIGINT to every process"),
                );
                stopping_since = Some(Instant::now());
                signals_seen_at_stop = signals;
                for slot in slots.iter_mut() {
                    match slot.state {
                        State::Running { pid } => signal_group(pid, Signal::SIGINT),
                        State::RespawnAt(_) => slot.state = State::Done,
                        State::Done => {}
                    }
                }
            }
        }
        if let Some(since) = stopping_since {
            let second_signal = signals > signals_seen_at_stop;
            if !killed && (since.elapsed() >= options.grace_period || second_signal) {
                killed = true;
                for slot in &slots {
                    if let State::Running { pid } = slot.state {
                        report(
                            sink,
                            &format!(
                                "[launch] [{}] still running: sending SIGKILL",
                                slot.spec.label
                            ),
                        );
                        signal_group(pid, Signal::SIGKILL);
                    }
                }
            }
        }
        if slots.iter().all(|s| matches!(s.state, State::Done)) {
            break;
        }
        let now = Instant::now();
        for i in 0..slots.len() {
            if matches!(slots[i].state, State::RespawnAt(at) if at <= now) {
                start(&mut slots, i, sink, &tx);
            }
        }
        match rx.recv_timeout(Duration::from_millis(20)) {
            Ok(exited) => on_exit(&mut slots, exited, stopping_since.is_some(), sink),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => unreachable!("the supervisor keeps a sender"),
        }
    }
    Ok(LaunchOutcome {
        interrupted,
        processes: slots
            .iter()
            .map(|s| ProcessReport {
                label: s.spec.label.clone(),
                starts: s.starts,
                last_exit: s
                    .last_exit
                    .clone()
                    .unwrap_or(ExitKind::NotStarted("never started".into())),
                failed: s.failed,
            })
            .collect(),
    })
}

fn on_exit(slots: &mut [Slot], exited: Exited, stopping: bool, sink: &OutputSink) {
    let slot = &mut slots[exited.slot];
    let kind = match exited.status {
        Ok(status) => match (status.code(), status.signal()) {
            (Some(code), _) => ExitKind::Code(code),
            (None, Some(sig)) => ExitKind::Signal(sig),
            (None, None) => ExitKind::Code(-1),
        },
        Err(e) => ExitKind::NotStarted(format!("waiting for it failed: {e}")),
    };
    let label = &slot.spec.label;
    report(sink, &format!("[launch] [{label}] {}", describe(&kind)));
    let unsuccessful = kind != ExitKind::Code(0);
    let restarts_done = slot.starts.saturating_sub(1);
    let may_restart = slot.spec.respawn
        && slot
            .spec
            .respawn_max_retries
            .map_or(true, |max| restarts_done < max);
    slot.last_exit = Some(kind);
    if stopping {
        slot.state = State::Done;
    } else if may_restart {
        let delay = slot.spec.respawn_delay;
        report(
            sink,
            &format!(
                "[launch] [{label}] respawning in {:.2} s",
                delay.as_secs_f64()
            ),
        );
        slot.state = State::RespawnAt(Instant::now() + delay);
    } else {
        slot.failed = unsuccessful;
        slot.state = State::Done;
    }
}

fn describe(kind: &ExitKind) -> String {
    match kind {
        ExitKind::Code(code) => format!("exited with code {code}"),
        ExitKind::Signal(sig) => {
            let name = Signal::try_from(*sig)
                .map(|s| s.as_str().to_string())
                .unwrap_or_else(|_| sig.to_string());
            format!("killed by signal {name}")
        }
        ExitKind::NotStarted(why) => format!("could not be started: {why}"),
    }
}

fn report(sink: &OutputSink, line: &str) {
    sink.write_line(Stream::Stderr, line);
}

fn signal_group(pid: i32, signal: Signal) {
    // ESRCH (already gone) is fine: the waiter thread will report the exit.
    let _ = killpg(Pid::from_raw(pid), signal);
}

/// Starts slot `i`: spawn in a new process group, start the two line-prefixing readers and the
/// waiter thread that reports the exit once the output has been drained.
fn start(slots: &mut [Slot], i: usize, sink: &OutputSink, tx: &Sender<Exited>) {
    let slot = &mut slots[i];
    let spec = slot.spec;
    let mut cmd = Command::new(&spec.program);
    cmd.args(&spec.args)
        .envs(spec.env.iter().map(|(k, v)| (k, v)))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0);
    if let Some(cwd) = &spec.cwd {
        cmd.current_dir(cwd);
    }
    // A launcher started with SIGINT ignored (e.g. as a background job of a script) would pass
    // that on, and its children could then only be stopped by SIGKILL: give them the default.
    // SAFETY: only async-signal-safe calls (signal(2)) between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            for sig in [Signal::SIGINT, Signal::SIGTERM] {
                nix::sys::signal::signal(sig, SigHandler::SigDfl).map_err(std::io::Error::from)?;
            }
            Ok(())
        });
    }
    let mut child = match cmd.spawn() {
        Ok(child) => child,
        Err(e) => {
            let kind = ExitKind::NotStarted(format!("{}: {e}", spec.program.display()));
            report(
                sink,
                &format!("[launch] [{}] {}", spec.label, describe(&kind)),
            );
            slot.last_exit = Some(kind);
            slot.failed = true;
            slot.state = State::Done;
            return;
        }
    };
    slot.starts += 1;
    let pid = child.id() as i32;
    slot.state = State::Running { pid };
    report(
        sink,
        &format!(
            "[launch] [{}] started, pid {pid}: {}",
            spec.label,
            spec.command_line().join(" ")
        ),
    );

    let open_readers = Arc::new((Mutex::new(2usize), Condvar::new()));
    let stdout = child
        .stdout
        .take()
        .map(|s| Box::new(s) as Box<dyn Read + Send>);
    let stderr = child
        .stderr
        .take()
        .map(|s| Box::new(s) as Box<dyn Read + Send>);
    for (pipe, stream) in [(stdout, Stream::Stdout), (stderr, Stream::Stderr)] {
        let sink = sink.clone();
        let label = spec.label.clone();
        let open = open_readers.clone();
        thread::spawn(move || {
            if let Some(pipe) = pipe {
                forward_lines(pipe, &label, stream, &sink);
            }
            let (count, cv) = &*open;
            *count.lock().unwrap_or_else(|p| p.into_inner()) -= 1;
            cv.notify_all();
        });
    }
    let tx = tx.clone();
    thread::spawn(move || {
        let status = child.wait();
        // Let the readers print what the process wrote before its exit is reported; a
        // grandchild that keeps the pipe open must not hold the report back for long.
        let (count, cv) = &*open_readers;
        let guard = count.lock().unwrap_or_else(|p| p.into_inner());
        let _ = cv.wait_timeout_while(guard, Duration::from_millis(500), |n| *n > 0);
        let _ = tx.send(Exited { slot: i, status });
    });
}

/// Copies `pipe` line by line to the sink as `[label] line`. Invalid UTF-8 is shown lossily.
fn forward_lines(pipe: Box<dyn Read + Send>, label: &str, stream: Stream, sink: &OutputSink) {
    let mut reader = BufReader::new(pipe);
    let mut buf = Vec::new();
    loop {
        buf.clear();
        match reader.read_until(b'\n', &mut buf) {
            Ok(0) | Err(_) => break,
            Ok(_) => {
                let text = String::from_utf8_lossy(&buf);
                let line = text.strip_suffix('\n').unwrap_or(&text);
                let line = line.strip_suffix('\r').unwrap_or(line);
                sink.write_line(stream, &format!("[{label}] {line}"));
            }
        }
    }
}
