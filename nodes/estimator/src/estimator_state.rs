//! The node's logic, the same live and on a bag: messages in, outputs out, no clock. Messages
//! go into a [`RecordStream`] (crates/records: the records `metrocell calibrate` and
//! `diagnose` build from a bag, here one at a time, judged on header stamps only), which holds a
//! measured point until every signal stream has a sample stamped at or after it (so the signals
//! at its time are final and a replay sees the same numbers as the live run), or until some
//! stream is `max_signal_gap` seconds past it. Records come out in stamp order and are taken by
//! the recursive estimator (crates/estimation `recursive`).

use std::collections::BTreeMap;

use metrocell_bagtools::SourcedMessage;
use metrocell_estimation::{MeasurementRecord, RecursiveEstimator, Update};
use metrocell_model::{ForwardModel, Workspace};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_records::RecordStream;
use nalgebra::{DMatrix, Vector3};

use crate::model_message;
use crate::observability_watch::{ObservabilityNote, ObservabilityWatch};
use crate::state_file::SavedState;

/// Settings that shape the outputs.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Publish the model after this many accepted measurements (and on every alarm).
    pub publish_every: u64,
    /// Joint vectors at which the volumetric error is predicted.
    pub predict_joints: Vec<Vec<f64>>,
    pub machine_id: String,
    /// Accepted measurements before a change in what the estimator holds is said (the end of a
    /// run says it regardless).
    pub quiet_until: u64,
}

/// What the node counts (diagnostics and the replay's summary).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Counters {
    pub points_received: u64,
    pub accepted: u64,
    pub outliers: u64,
    pub alarms: u64,
    /// By reason: rejected (not finite, no signals at its time, … — the log says which),
    /// model_error.
    pub points_not_used: BTreeMap<&'static str, u64>,
    /// Signal samples refused (no machine joints in a joint state, a time going backwards, a
    /// NaN, a message that does not decode).
    pub refused_samples: u64,
    pub models_published: u64,
}

impl Counters {
    pub fn summary(&self) -> String {
        let not_used = self
            .points_not_used
            .iter()
            .map(|(r, n)| format!("{r}: {n}"))
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "{} points received, {} accepted, {} gated as outliers, {} alarms, not used: [{not_used}], {} models published, {} signal samples refused",
            self.points_received, self.accepted, self.outliers, self.alarms, self.models_published, self.refused_samples
        )
    }
}

/// The model stopped explaining the data: where and how badly.
#[derive(Debug, Clone, PartialEq)]
pub struct Alarm {
    pub stamp_ns: i64,
    pub point_id: String,
    /// Measurements taken (accepted or gated) before this one.
    pub measurement: u64,
    pub nis: f64,
    pub window_probability: f64,
    pub innovation: Vector3<f64>,
}

/// What one processed point produced.
#[derive(Debug, Clone, Default)]
pub struct Outputs {
    pub model: Option<ErrorModel>,
    pub predicted: Vec<MeasuredPoint>,
    pub alarm: Option<Alarm>,
    /// A point that could not be used, and why (for the log).
    pub problem: Option<String>,
    /// What the estimator holds (unobservable, at a bound) changed.
    pub observability: Option<ObservabilityNote>,
}

pub struct EstimatorState<'m> {
    model: &'m ForwardModel<'m>,
    filter: RecursiveEstimator,
    work: Workspace,
    jacobian: DMatrix<f64>,
    stream: RecordStream<'m, 'm>,
    points_topic: String,
    settings: Settings,
    since_publish: u64,
    observability: ObservabilityWatch,
    pub counters: Counters,
}

impl<'m> EstimatorState<'m> {
    /// `stream` reads the points from `points_topic`.
    pub fn new(
        model: &'m ForwardModel<'m>,
        filter: RecursiveEstimator,
        stream: RecordStream<'m, 'm>,
        points_topic: String,
        settings: Settings,
    ) -> Self {
        let n = model.param_count();
        let observability = ObservabilityWatch::new(model.param_names(), settings.quiet_until);
        Self {
            work: Workspace::new(model),
            jacobian: DMatrix::zeros(3, n),
            model,
            filter,
            stream,
            points_topic,
            settings,
            since_publish: 0,
            observability,
            counters: Counters::default(),
        }
    }

    pub fn filter(&self) -> &RecursiveEstimator {
        &self.filter
    }

    /// What the estimator holds at the end of a run (or now), analysed afresh.
    pub fn observability_now(&mut self, stamp_ns: i64) -> ObservabilityNote {
        self.observability.final_note(&self.filter, stamp_ns)
    }

    /// The state to restart from (see [`crate::state_file`]).
    pub fn saved_state(&self, stamp_ns: i64) -> SavedState {
        let names = self.model.param_names();
        let free = self.filter.free_indices();
        let p = self.filter.covariance();
        let k = free.len();
        SavedState {
            free: free.iter().map(|&i| names[i].clone()).collect(),
            parameter_names: names,
            values: self.filter.state().to_vec(),
            covariance: (0..k * k).map(|i| p[(i / k, i % k)]).collect(),
            stamp_ns,
        }
    }

    /// Points still waiting for their signals.
    pub fn pending(&self) -> usize {
        self.stream.waiting()
    }

    /// The topics the state reads.
    pub fn topics(&self) -> Vec<String> {
        self.stream.topics()
    }

    /// One input message (a measured point, a commanded joint state, a signal); others are
    /// ignored. A message the recording cannot use at all is returned as the reason.
    pub fn message(&mut self, m: &SourcedMessage) -> Result<(), String> {
        if m.topic == self.points_topic {
            self.counters.points_received += 1;
        }
        let pushed = self.stream.push(m).map_err(|e| e.to_string());
        self.counters.refused_samples = self.stream.refused_samples();
        pushed
    }

    /// Take every record whose signals are final, in stamp order.
    pub fn process(&mut self) -> Vec<Outputs> {
        let mut resolved = self.stream.drain();
        let mut out: Vec<Outputs> = std::mem::take(&mut resolved.rejected)
            .into_iter()
            .map(|r| {
                self.not_used(
                    "rejected",
                    format!("point {} ({}): {}; skipped", r.point_id, r.at, r.reason),
                )
            })
            .collect();
        for record in resolved.records() {
            out.push(self.take(record));
        }
        out
    }

    fn not_used(&mut self, reason: &'static str, message: String) -> Outputs {
        *self.counters.points_not_used.entry(reason).or_default() += 1;
        Outputs {
            problem: Some(message),
            ..Default::default()
        }
    }

    fn take(&mut self, record: MeasurementRecord) -> Outputs {
        let stamp_ns = (record.time * 1e9).round() as i64;
        let measurement = self.counters.accepted + self.counters.outliers;
        let update: Update = match self.filter.update(self.model, &record, &mut self.work) {
            Ok(u) => u,
            Err(e) => {
                return self.not_used(
                    "model_error",
                    format!(
                        "point {} at {:.3} s: {e}; skipped",
                        record.point_id, record.time
                    ),
                )
            }
        };
        let mut out = Outputs::default();
        if update.accepted {
            self.counters.accepted += 1;
            self.since_publish += 1;
        } else {
            self.counters.outliers += 1;
        }
        if update.alarm {
            self.counters.alarms += 1;
            out.alarm = Some(Alarm {
                stamp_ns,
                point_id: record.point_id.clone(),
                measurement,
                nis: update.nis,
                window_probability: update.window_probability,
                innovation: update.innovation,
            });
        }
        if update.accepted || update.alarm {
            out.observability =
                self.observability
                    .after_update(&self.filter, update.alarm, stamp_ns);
        }
        if update.alarm || self.since_publish >= self.settings.publish_every {
            self.since_publish = 0;
            out.model = Some(model_message::error_model(
                self.model,
                &self.filter,
                &self.settings.machine_id,
                stamp_ns,
                self.observability.unobserved_directions(),
            ));
            out.predicted = self.predictions(&record.signals, stamp_ns);
            self.counters.models_published += 1;
        }
        out
    }

    /// The predicted volumetric error at each configured joint vector, with its covariance from
    /// the filter's: nominal = nominal tool point, measured = true tool point.
    fn predictions(
        &mut self,
        at: &metrocell_physics::Signals,
        header_ns: i64,
    ) -> Vec<MeasuredPoint> {
        let x = self.filter.state().to_vec();
        let Ok(kin) = self.model.kinematic_truth(&x) else {
            return Vec::new();
        };
        let mut out = Vec::with_capacity(self.settings.predict_joints.len());
        for (k, q) in self.settings.predict_joints.iter().enumerate() {
            let mut s = at.clone();
            // standing at the point, approached in the positive direction
            self.model
                .set_motion(&mut s, q, &vec![0.0; q.len()], &vec![1.0; q.len()]);
            let Ok(state) = self.model.tool_state(&x, &kin, q, &mut s, None) else {
                continue;
            };
            if self
                .model
                .tool_point_jacobian(&x, &kin, q, &mut s, &mut self.jacobian)
                .is_err()
            {
                continue;
            }
            let cov = model_message::propagate(&self.jacobian, &self.filter);
            out.push(model_message::predicted_point(
                k,
                &state.nominal.translation.vector,
                &state.truth.translation.vector,
                &cov,
                header_ns,
            ));
        }
        out
    }
}
