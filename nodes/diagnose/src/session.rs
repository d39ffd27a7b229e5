//! One diagnosis session: messages in (live or from a bag), records out of a
//! [`RecordStream`], the [`SlidingWindow`] over them, and a diagnosis of the window whenever one
//! is due. The node runs the diagnosis itself on a worker thread (it takes seconds) and
//! publishes the [`Outcome`]; a replay runs it in line.

use std::path::Path;

use metrocell_bagtools::SourcedMessage;
use metrocell_diagnose::{diagnose, DiagnoseError, Diagnosis};
use metrocell_model::ForwardModel;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::std_msgs::msg::String as StringMessage;
use metrocell_records::{RecordStream, RecordingError};

use crate::findings_message::{diagnosis_message, Announced, RunInfo};
use crate::parameters::Setup;
use crate::sliding_window::SlidingWindow;

pub struct Session<'m> {
    pub setup: Setup,
    pub stream: RecordStream<'m, 'm>,
    pub window: SlidingWindow,
    announced: Announced,
    runs: u64,
}

/// A diagnosis to run: the window's records and what they cover.
pub struct Job {
    pub records: crate::sliding_window::WindowSnapshot,
    pub info: RunInfo,
}

/// What a run gives the world: the statuses, the JSON result (the same fields as `metrocell
/// diagnose --json`) and the findings not announced before.
pub struct Outcome {
    pub statuses: DiagnosticArray,
    pub result: StringMessage,
    pub new_findings: Vec<String>,
    pub summary: String,
}

impl<'m> Session<'m> {
    /// `source` names the recording in messages (the bag, or `live DDS`); `topics` are the
    /// (name, type) the session will be fed; `forward` is the forward model of `setup.model`
    /// (the record stream borrows it).
    pub fn new(
        setup: Setup,
        forward: &'m ForwardModel<'m>,
        source: &Path,
        topics: &[(String, String)],
    ) -> Result<Self, RecordingError> {
        let stream = RecordStream::new(source, topics, forward, &setup.recording)?;
        let window = SlidingWindow::new(setup.window);
        Ok(Self {
            setup,
            stream,
            window,
            announced: Announced::default(),
            runs: 0,
        })
    }

    /// Take one message.
    pub fn push(&mut self, m: &SourcedMessage) -> Result<(), RecordingError> {
        self.stream.push(m)?;
        self.window.take(self.stream.drain());
        Ok(())
    }

    /// The end of the recording: measurements still waiting for signals are answered as the
    /// signals stand.
    pub fn flush(&mut self) {
        self.stream.flush();
        self.window.take(self.stream.drain());
    }

    /// Diagnoses run so far.
    pub fn runs(&self) -> u64 {
        self.runs
    }

    /// A diagnosis of the window, if one is due.
    pub fn due_job(&mut self) -> Option<Job> {
        self.window.due().then(|| self.job())
    }

    /// The window as it stands, as a job (e.g. at the end of a replay).
    pub fn job(&mut self) -> Job {
        let records = self.window.snapshot();
        self.runs += 1;
        let from = records.records.first().map_or(0.0, |r| r.time);
        let to = records.records.last().map_or(0.0, |r| r.time);
        Job {
            records,
            info: RunInfo {
                from,
                to,
                run: self.runs,
            },
        }
    }

    /// Turn a run's result into what is published (module docs); an error (too few records to
    /// tell candidates apart, …) becomes an OK status that says what is missing.
    pub fn outcome(
        &mut self,
        info: &RunInfo,
        result: &Result<Diagnosis, DiagnoseError>,
        stamp_ns: i64,
        hardware_id: &str,
    ) -> Outcome {
        match result {
            Ok(d) => {
                let json = serde_json::to_string(&d.report).expect("a report serialises");
                Outcome {
                    statuses: diagnosis_message(d, info, stamp_ns, hardware_id),
                    result: StringMessage { data: json },
                    new_findings: self.announced.new_findings(d),
                    summary: format!(
                        "run {} over {:.2} h of cell time ({} records): {}",
                        info.run,
                        (info.to - info.from) / 3600.0,
                        d.report.records.used,
                        d.report.summary
                    ),
                }
            }
            Err(e) => {
                let message = format!("run {}: not diagnosed yet: {e}", info.run);
                let statuses =
                    crate::findings_message::waiting_message(&message, stamp_ns, hardware_id);
                Outcome {
                    statuses,
                    result: StringMessage {
                        data: serde_json::json!({ "error": e.to_string(), "run": info.run })
                            .to_string(),
                    },
                    new_findings: Vec::new(),
                    summary: message,
                }
            }
        }
    }
}

/// Run a job (what the worker thread does): the diagnosis, then its working memory (copies of
/// the window's records, Jacobians of every candidate: 150–180 MB over an hour's window) freed
/// and handed back to the system.
pub fn run_job(
    setup_declared: &metrocell_diagnose::DeclaredModel,
    options: &metrocell_diagnose::DiagnoseOptions,
    job: Job,
) -> (RunInfo, Result<Diagnosis, DiagnoseError>) {
    let Job { records, info } = job;
    // the copies are made here, on the worker's thread (see `SlidingWindow::records`)
    let records = records.into_record_set();
    let result = diagnose(setup_declared, &records, options);
    drop(records);
    release_freed_memory();
    (info, result)
}

/// glibc keeps freed memory in its arenas for the next allocation, so without this the node's
/// resident size stays at the peak of its largest diagnosis (measured on the demo's 5-h bag:
/// 132 → 634 MB over four diagnoses; BENCHMARKS.md, *A shift under metrocell demo*). Elsewhere
/// (musl, other systems) this does nothing.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn release_freed_memory() {
    // SAFETY: malloc_trim only returns free pages of glibc's arenas to the kernel; it touches no
    // live allocation.
    unsafe {
        libc::malloc_trim(0);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn release_freed_memory() {}
