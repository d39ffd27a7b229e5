//! The node's logic, the same live and on a bag: messages in, outputs out, no clock. A measured
//! point waits until every signal stream has passed its stamp (so the signals at its time are
//! final and a replay sees the same numbers as the live run), or until some stream is
//! `signal_wait` seconds past it (a dead sensor must not stall the estimate: the last value
//! holds, and the point is counted as `points_with_held_signals`). Points are then taken in
//! stamp order by the recursive estimator (crates/estimation `recursive`).

use std::collections::BTreeMap;

use metrocell_estimation::{MeasurementRecord, RecordKind, RecursiveEstimator, Update};
use metrocell_model::{ForwardModel, Workspace};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::{JointState, Temperature};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::model_message;
use crate::signal_stream::SignalStream;
use crate::state_file::SavedState;

/// Settings that shape the outputs.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Publish the model after this many accepted measurements (and on every alarm).
    pub publish_every: u64,
    /// s of stamp time a point waits for a stream that has stopped.
    pub signal_wait: f64,
    /// Joint vectors at which the volumetric error is predicted.
    pub predict_joints: Vec<Vec<f64>>,
    pub machine_id: String,
}

/// What the node counts (diagnostics and the replay's summary).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Counters {
    pub points_received: u64,
    pub accepted: u64,
    pub outliers: u64,
    pub alarms: u64,
    pub points_with_held_signals: u64,
    /// By reason: not_finite, no_signals, model_error.
    pub points_not_used: BTreeMap<&'static str, u64>,
    pub joint_states_without_axes: u64,
    pub rejected_readings: u64,
    pub models_published: u64,
}

impl Counters {
    pub fn summary(&self) -> String {
        let not_used = self.points_not_used.iter().map(|(r, n)| format!("{r}: {n}")).collect::<Vec<_>>().join(", ");
        format!(
            "{} points received, {} accepted, {} gated as outliers, {} alarms, {} with held signals, not used: [{not_used}], {} models published, {} joint states without the machine's joints, {} temperature readings rejected",
            self.points_received, self.accepted, self.outliers, self.alarms, self.points_with_held_signals, self.models_published, self.joint_states_without_axes, self.rejected_readings
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
}

pub struct EstimatorState {
    model: ForwardModel<'static>,
    filter: RecursiveEstimator,
    work: Workspace,
    jacobian: DMatrix<f64>,
    stream: SignalStream,
    joint_names: Vec<String>,
    /// Points waiting for their signals, by (stamp ns, arrival) — arrival breaks ties in order.
    pending: BTreeMap<(i64, u64), MeasuredPoint>,
    arrivals: u64,
    settings: Settings,
    since_publish: u64,
    pub counters: Counters,
}

impl EstimatorState {
    pub fn new(model: ForwardModel<'static>, filter: RecursiveEstimator, stream: SignalStream, settings: Settings) -> Self {
        let n = model.param_count();
        Self {
            joint_names: model.machine.joint_names(),
            work: Workspace::new(&model),
            jacobian: DMatrix::zeros(3, n),
            model,
            filter,
            stream,
            pending: BTreeMap::new(),
            arrivals: 0,
            settings,
            since_publish: 0,
            counters: Counters::default(),
        }
    }

    pub fn filter(&self) -> &RecursiveEstimator {
        &self.filter
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
        self.pending.len()
    }

    /// A commanded joint state: the family's joints picked by name.
    pub fn joint_state(&mut self, js: &JointState) {
        let index: Option<Vec<usize>> = self.joint_names.iter().map(|n| js.name.iter().position(|m| m == n)).collect();
        let Some(index) = index.filter(|i| i.iter().all(|&k| k < js.position.len())) else {
            self.counters.joint_states_without_axes += 1;
            return;
        };
        let q = index.iter().map(|&k| js.position[k]).collect();
        let velocity = (js.velocity.len() == js.name.len()).then(|| index.iter().map(|&k| js.velocity[k]).collect());
        self.stream.joints(js.header.stamp.nanos() as f64 * 1e-9, q, velocity);
    }

    /// A temperature reading of `sensor`.
    pub fn temperature(&mut self, sensor: &str, t: &Temperature) {
        if !self.stream.temperature(sensor, t.header.stamp.nanos() as f64 * 1e-9, t.temperature) {
            self.counters.rejected_readings += 1;
        }
    }

    /// A measured point (machine frame): queued until its signals are final.
    pub fn point(&mut self, p: MeasuredPoint) {
        self.counters.points_received += 1;
        self.arrivals += 1;
        self.pending.insert((p.header.stamp.nanos(), self.arrivals), p);
    }

    /// Take every queued point whose signals are final (or held), in stamp order.
    pub fn process(&mut self) -> Vec<Outputs> {
        let mut out = Vec::new();
        while let Some((&(ns, _), _)) = self.pending.first_key_value() {
            let t = ns as f64 * 1e-9;
            let held = !self.stream.covers(t);
            if held && !self.stream.newest().is_some_and(|newest| newest - t > self.settings.signal_wait) {
                break;
            }
            let (_, p) = self.pending.pop_first().expect("looked at above");
            if held {
                self.counters.points_with_held_signals += 1;
            }
            out.push(self.take(&p, t));
            self.stream.forget_before(t);
        }
        out
    }

    fn not_used(&mut self, reason: &'static str, message: String) -> Outputs {
        *self.counters.points_not_used.entry(reason).or_default() += 1;
        Outputs { problem: Some(message), ..Default::default() }
    }

    fn take(&mut self, p: &MeasuredPoint, t: f64) -> Outputs {
        let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
        let covariance = Matrix3::from_row_slice(&p.covariance);
        if !(measured.iter().chain(covariance.iter()).all(|v| v.is_finite())) {
            return self.not_used("not_finite", format!("point {} at {t:.3} s: not finite (measured or covariance); skipped", p.point_id));
        }
        let (q, velocity, approach, mut signals) = match self.stream.at(t) {
            Ok(s) => s,
            Err(gap) => return self.not_used("no_signals", format!("point {} at {t:.3} s: {gap}; skipped", p.point_id)),
        };
        self.model.set_motion(&mut signals, &q, &velocity, &approach);
        let record = MeasurementRecord { time: t, point_id: p.point_id.clone(), channel: p.source.clone(), q, measured, covariance, signals, kind: RecordKind::Point };
        let measurement = self.counters.accepted + self.counters.outliers;
        let update: Update = match self.filter.update(&self.model, &record, &mut self.work) {
            Ok(u) => u,
            Err(e) => return self.not_used("model_error", format!("point {} at {t:.3} s: {e}; skipped", p.point_id)),
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
            out.alarm = Some(Alarm { stamp_ns: p.header.stamp.nanos(), point_id: p.point_id.clone(), measurement, nis: update.nis, window_probability: update.window_probability, innovation: update.innovation });
        }
        if update.alarm || self.since_publish >= self.settings.publish_every {
            self.since_publish = 0;
            let header_ns = p.header.stamp.nanos();
            out.model = Some(model_message::error_model(&self.model, &self.filter, &self.settings.machine_id, header_ns));
            out.predicted = self.predictions(&record.signals, header_ns);
            self.counters.models_published += 1;
        }
        out
    }

    /// The predicted volumetric error at each configured joint vector, with its covariance from
    /// the filter's: nominal = nominal tool point, measured = true tool point.
    fn predictions(&mut self, at: &metrocell_physics::Signals, header_ns: i64) -> Vec<MeasuredPoint> {
        let x = self.filter.state().to_vec();
        let Ok(kin) = self.model.kinematic_truth(&x) else { return Vec::new() };
        let mut out = Vec::with_capacity(self.settings.predict_joints.len());
        for (k, q) in self.settings.predict_joints.iter().enumerate() {
            let mut s = at.clone();
            // standing at the point, approached in the positive direction
            self.model.set_motion(&mut s, q, &vec![0.0; q.len()], &vec![1.0; q.len()]);
            let Ok(state) = self.model.tool_state(&x, &kin, q, &mut s, None) else { continue };
            if self.model.tool_point_jacobian(&x, &kin, q, &mut s, &mut self.jacobian).is_err() {
                continue;
            }
            let cov = model_message::propagate(&self.jacobian, &self.filter);
            out.push(model_message::predicted_point(k, &state.nominal.translation.vector, &state.truth.translation.vector, &cov, header_ns));
        }
        out
    }
}
