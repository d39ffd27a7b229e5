//! The records of the last `window` seconds of cell time, and when to diagnose them again.
//!
//! Records arrive from a [`metrocell_records::RecordStream`] in time order per kind (points,
//! probe hits). The window holds those whose time lies within `window` of the newest; a run is
//! due once `every` seconds of cell time have passed since the last one and the window holds at
//! least `min_records`. Time is the records' own (their header stamps): a shift replayed from a
//! bag at any speed, or a twin running 100× real time, is diagnosed at the same cell instants.

use std::collections::VecDeque;
use std::sync::Arc;

use metrocell_estimation::{MeasurementRecord, RecordFrame, RecordSet, Rejected};
use metrocell_records::StreamOutput;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowSettings {
    /// Cell time the window spans [s].
    pub window_s: f64,
    /// Cell time between two diagnoses [s].
    pub every_s: f64,
    /// Fewest records worth diagnosing.
    pub min_records: usize,
}

/// The window and its schedule (module docs).
#[derive(Debug)]
pub struct SlidingWindow {
    settings: WindowSettings,
    /// Shared, so a snapshot is a list of pointers: the copies a diagnosis works on are made on
    /// its worker thread ([`WindowSnapshot::into_record_set`]), in that thread's allocator arena,
    /// and freed there, not in the arena the window keeps allocating in. (After some diagnoses
    /// the node still holds 20–40 MB more until the next one — glibc's arenas, not growth: the
    /// soak judges this node by its end and trend, BENCHMARKS.md.)
    records: VecDeque<Arc<MeasurementRecord>>,
    /// The points' frame (the first one seen); points in another frame are set aside.
    frame: Option<RecordFrame>,
    /// Rejections since the last run, handed to it (they are part of its report).
    rejected: Vec<Rejected>,
    sources: Vec<(String, String)>,
    newest: f64,
    /// Cell time of the first record ever taken: the schedule's start.
    first: Option<f64>,
    last_run: Option<f64>,
    /// Every record taken in, and those dropped out of the window's back.
    pub taken: u64,
    pub expired: u64,
}

impl SlidingWindow {
    pub fn new(settings: WindowSettings) -> Self {
        Self {
            settings,
            records: VecDeque::new(),
            frame: None,
            rejected: Vec::new(),
            sources: Vec::new(),
            newest: f64::NEG_INFINITY,
            first: None,
            last_run: None,
            taken: 0,
            expired: 0,
        }
    }

    /// Take what a record stream resolved.
    pub fn take(&mut self, out: StreamOutput) {
        self.sources = out.sources;
        self.rejected.extend(out.rejected);
        for (frame, records) in out.by_frame {
            let frame_now = self.frame.get_or_insert_with(|| frame.clone());
            if *frame_now != frame {
                for r in records {
                    self.rejected.push(Rejected {
                        at: format!("t = {:.3} s", r.time),
                        point_id: r.point_id,
                        reason: format!(
                            "in frame {frame:?}, while this window's points are in {frame_now:?}"
                        ),
                    });
                }
                continue;
            }
            self.push_all(records);
        }
        self.push_all(out.instrument_records);
        let oldest = self.newest - self.settings.window_s;
        let before = self.records.len();
        self.records.retain(|r| r.time >= oldest);
        self.expired += (before - self.records.len()) as u64;
    }

    fn push_all(&mut self, records: Vec<MeasurementRecord>) {
        for r in records {
            self.newest = self.newest.max(r.time);
            self.first.get_or_insert(r.time);
            self.taken += 1;
            self.records.push_back(Arc::new(r));
        }
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Whether records came in since the last run (or there was none yet).
    pub fn has_new_records(&self) -> bool {
        !self.records.is_empty() && self.last_run.is_none_or(|t| self.newest > t)
    }

    /// Whether a diagnosis of the window is due (module docs).
    pub fn due(&self) -> bool {
        let since = self.last_run.or(self.first).unwrap_or(self.newest);
        self.records.len() >= self.settings.min_records
            && self.newest - since >= self.settings.every_s
    }

    /// The window's records (time order), and the rejections since the last run; the schedule
    /// restarts from the newest record.
    pub fn snapshot(&mut self) -> WindowSnapshot {
        self.last_run = Some(self.newest);
        let mut records: Vec<Arc<MeasurementRecord>> = self.records.iter().cloned().collect();
        records.sort_by(|a, b| a.time.total_cmp(&b.time));
        WindowSnapshot {
            frame: self.frame.clone().unwrap_or(RecordFrame::Machine),
            records,
            rejected: std::mem::take(&mut self.rejected),
            sources: self.sources.clone(),
        }
    }
}

/// The window at one instant, sharing its records with it.
#[derive(Debug)]
pub struct WindowSnapshot {
    pub frame: RecordFrame,
    /// Time order.
    pub records: Vec<Arc<MeasurementRecord>>,
    pub rejected: Vec<Rejected>,
    pub sources: Vec<(String, String)>,
}

impl WindowSnapshot {
    /// The records as the set a diagnosis takes: copies, made by the thread that calls this.
    pub fn into_record_set(self) -> RecordSet {
        RecordSet {
            check: Vec::new(),
            frame: self.frame,
            records: self.records.iter().map(|r| (**r).clone()).collect(),
            rejected: self.rejected,
            sources: self.sources,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_estimation::RecordKind;

    fn record(t: f64) -> MeasurementRecord {
        MeasurementRecord {
            time: t,
            point_id: format!("p{t}"),
            channel: "tracker".into(),
            q: vec![0.0; 3],
            measured: Default::default(),
            covariance: Default::default(),
            signals: Default::default(),
            kind: RecordKind::Point,
        }
    }

    fn output(times: &[f64]) -> StreamOutput {
        StreamOutput {
            by_frame: vec![(
                RecordFrame::Machine,
                times.iter().map(|&t| record(t)).collect(),
            )],
            ..Default::default()
        }
    }

    #[test]
    fn keeps_the_last_window_and_runs_every_period() {
        let mut w = SlidingWindow::new(WindowSettings {
            window_s: 100.0,
            every_s: 50.0,
            min_records: 3,
        });
        w.take(output(&[0.0, 10.0]));
        assert!(!w.due(), "two records are fewer than min_records");
        w.take(output(&[20.0]));
        assert!(!w.due(), "20 s since the first record");
        w.take(output(&[50.0]));
        assert!(w.due());
        let set = w.snapshot();
        assert_eq!(set.records.len(), 4);
        assert!(!w.due(), "just ran");
        w.take(output(&[60.0]));
        assert!(!w.due(), "10 s since the last run");
        w.take(output(&[70.0, 115.0]));
        assert!(w.due(), "65 s since the last run");
        let set = w.snapshot();
        // 115 − 100 = 15: the records at 0 and 10 have left the window
        assert_eq!(
            set.records.iter().map(|r| r.time).collect::<Vec<_>>(),
            vec![20.0, 50.0, 60.0, 70.0, 115.0]
        );
        assert_eq!((w.taken, w.expired), (7, 2));
    }

    #[test]
    fn points_in_another_frame_are_set_aside_with_the_reason() {
        let mut w = SlidingWindow::new(WindowSettings {
            window_s: 100.0,
            every_s: 1.0,
            min_records: 1,
        });
        w.take(output(&[0.0, 1.0]));
        w.take(StreamOutput {
            by_frame: vec![(RecordFrame::Instrument("tracker".into()), vec![record(2.0)])],
            ..Default::default()
        });
        let set = w.snapshot();
        assert_eq!(set.records.len(), 2);
        assert_eq!(set.rejected.len(), 1);
        assert!(
            set.rejected[0].reason.contains("frame"),
            "{:?}",
            set.rejected
        );
    }
}
