//! Residuals of measurement records against the shared forward model, as a least-squares problem.
//!
//! Convention: residual = measured − predicted, in the frame of each record (see
//! [`crate::records`]: a point in the set's frame, a probe hit's stylus-centre reading in the
//! workpiece frame, a camera point in the camera frame), over the full stacked parameter vector of the [`ForwardModel`] (machine
//! terms, then instrument terms; which are free is the solver's `fixed` mask). Each record
//! contributes three rows whitened by its covariance: with Σ = L·Lᵀ (Cholesky), the rows are
//! L⁻¹·(measured − predicted), so correlated coordinates (a tracker's point is far more
//! uncertain across the beam than along it) are weighted correctly and a whitened residual of
//! an honest measurement has unit variance. The Jacobian is the model's analytic one
//! ([`ForwardModel::tracker_jacobian`] rows of the reported point,
//! [`ForwardModel::probe_jacobian`], [`ForwardModel::camera_jacobian`] rows of the camera point),
//! negated and whitened.

use std::cell::RefCell;

use metrocell_model::{ForwardModel, KinematicTruth, Workspace, CAMERA_ROWS, PROBE_ROWS, TRACKER_ROWS};
use metrocell_physics::{PhysicsError, Signals};
use metrocell_solver::{NotEvaluable, Problem};
use nalgebra::{DMatrix, DMatrixView, Matrix3, Vector3};

use crate::records::{MeasurementRecord, RecordKind};

/// Measurement records (points, probe hits, camera points) against the model.
pub struct PointResiduals<'m, 'a> {
    model: &'m ForwardModel<'a>,
    records: &'m [MeasurementRecord],
    /// L⁻¹ of each record's covariance.
    whitening: Vec<Matrix3<f64>>,
    scratch: RefCell<Scratch>,
}

struct Scratch {
    signals: Vec<Signals>,
    buffers: Buffers,
}

/// A record that cannot be used: its covariance is not positive definite or not finite.
#[derive(Debug, Clone, PartialEq)]
pub struct BadCovariance {
    pub index: usize,
    pub point_id: String,
}

/// L⁻¹ with Σ = L·Lᵀ, or None if Σ is not finite and positive definite.
pub fn whitening(covariance: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    if !covariance.iter().all(|v| v.is_finite()) {
        return None;
    }
    let l = covariance.cholesky()?.l();
    l.try_inverse()
}

impl<'m, 'a> PointResiduals<'m, 'a> {
    pub fn new(model: &'m ForwardModel<'a>, records: &'m [MeasurementRecord]) -> Result<Self, BadCovariance> {
        let whitening = records
            .iter()
            .enumerate()
            .map(|(index, r)| whitening(&r.covariance).ok_or_else(|| BadCovariance { index, point_id: r.point_id.clone() }))
            .collect::<Result<Vec<_>, _>>()?;
        let scratch = Scratch { signals: records.iter().map(|r| r.signals.clone()).collect(), buffers: Buffers::new(model) };
        Ok(Self { model, records, whitening, scratch: RefCell::new(scratch) })
    }

    pub fn model(&self) -> &ForwardModel<'a> {
        self.model
    }

    pub fn records(&self) -> &[MeasurementRecord] {
        self.records
    }

    /// The whitening L⁻¹ of record `i`.
    pub fn whitening_of(&self, i: usize) -> &Matrix3<f64> {
        &self.whitening[i]
    }

    /// The predicted measurement of every record at parameters `p` (each in its record's frame), m.
    pub fn predictions(&self, p: &[f64]) -> Result<Vec<Vector3<f64>>, PhysicsError> {
        let kin = self.model.kinematic_truth(p)?;
        let mut scratch = self.scratch.borrow_mut();
        let mut out = Vec::with_capacity(self.records.len());
        for (r, s) in self.records.iter().zip(scratch.signals.iter_mut()) {
            out.push(predict(self.model, p, &kin, r, s)?);
        }
        Ok(out)
    }

    /// measured − predicted of every record at `p`, m (unwhitened).
    pub fn raw_residuals(&self, p: &[f64]) -> Result<Vec<Vector3<f64>>, PhysicsError> {
        Ok(self.predictions(p)?.iter().zip(self.records).map(|(pred, r)| r.measured - pred).collect())
    }

    /// The Jacobian of the predictions w.r.t. the stacked parameters (3·records × n,
    /// unwhitened, rows x y z of each record in turn) at `p`.
    pub fn prediction_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, PhysicsError> {
        let kin = self.model.kinematic_truth(p)?;
        let n = self.model.param_count();
        let mut out = DMatrix::zeros(3 * self.records.len(), n);
        let mut scratch = self.scratch.borrow_mut();
        let Scratch { signals, buffers } = &mut *scratch;
        for (i, (r, s)) in self.records.iter().zip(signals.iter_mut()).enumerate() {
            let (_, rows) = buffers.predict_with_jacobian(self.model, p, &kin, r, s)?;
            out.rows_mut(3 * i, 3).copy_from(&rows);
        }
        Ok(out)
    }

    fn evaluate(&self, p: &[f64], residuals: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) -> Result<(), NotEvaluable> {
        let fail = |i: usize, e: PhysicsError| NotEvaluable(format!("record {i} ({}): {e}", self.records[i].point_id));
        let kin: KinematicTruth = self.model.kinematic_truth(p).map_err(|e| NotEvaluable(e.to_string()))?;
        let mut scratch = self.scratch.borrow_mut();
        let Scratch { signals, buffers } = &mut *scratch;
        for (i, (r, s)) in self.records.iter().zip(signals.iter_mut()).enumerate() {
            let w = &self.whitening[i];
            let predicted = match jac.as_deref_mut() {
                Some(out) => {
                    let (pred, rows) = buffers.predict_with_jacobian(self.model, p, &kin, r, s).map_err(|e| fail(i, e))?;
                    // ∂r/∂p = −L⁻¹·∂prediction/∂p
                    out.rows_mut(3 * i, 3).gemm(-1.0, w, &rows, 0.0);
                    pred
                }
                None => predict(self.model, p, &kin, r, s).map_err(|e| fail(i, e))?,
            };
            let z = w * (r.measured - predicted);
            if !z.iter().all(|v| v.is_finite()) {
                return Err(NotEvaluable(format!("record {i} ({}): residual not finite", r.point_id)));
            }
            residuals[3 * i..3 * i + 3].copy_from_slice(z.as_slice());
        }
        Ok(())
    }
}

/// The model's prediction of record `r` at `p` (signals `s`), in the record's frame: a point
/// through the tracker, a probe hit through its probe, a camera point through its camera.
pub fn predict(model: &ForwardModel, p: &[f64], kin: &KinematicTruth, r: &MeasurementRecord, s: &mut Signals) -> Result<Vector3<f64>, PhysicsError> {
    match &r.kind {
        RecordKind::Point => {
            let tool = model.tool_state(p, kin, &r.q, s, None)?;
            Ok(model.tracker(p, &tool, s)?.measured_point())
        }
        RecordKind::ProbeHit { target, probe } => Ok(model.probe_hit(probe.as_deref(), p, kin, &r.q, s, target)?.centre),
        RecordKind::CameraPoint { feature, camera } => {
            let tool = model.tool_state(p, kin, &r.q, s, None)?;
            Ok(model.camera(camera.as_deref(), p, &tool, s, feature)?.measured_point)
        }
    }
}

/// The model's Jacobian buffers, one per reading kind (allocated once per problem).
struct Buffers {
    work: Workspace,
    tracker: DMatrix<f64>,
    probe: DMatrix<f64>,
    camera: DMatrix<f64>,
}

impl Buffers {
    fn new(model: &ForwardModel) -> Self {
        let n = model.param_count();
        Self { work: Workspace::new(model), tracker: DMatrix::zeros(TRACKER_ROWS, n), probe: DMatrix::zeros(PROBE_ROWS, n), camera: DMatrix::zeros(CAMERA_ROWS, n) }
    }

    /// [`predict`] (bit for bit) and the three rows of its Jacobian (a view into the buffers).
    fn predict_with_jacobian(&mut self, model: &ForwardModel, p: &[f64], kin: &KinematicTruth, r: &MeasurementRecord, s: &mut Signals) -> Result<(Vector3<f64>, DMatrixView<'_, f64>), PhysicsError> {
        Ok(match &r.kind {
            RecordKind::Point => {
                let pred = model.tracker_jacobian(p, kin, &r.q, s, &mut self.work, &mut self.tracker)?;
                (pred.measured_point(), self.tracker.rows(0, 3))
            }
            RecordKind::ProbeHit { target, probe } => {
                let pred = model.probe_jacobian(probe.as_deref(), p, kin, &r.q, s, target, &mut self.work, &mut self.probe)?;
                (pred.centre, self.probe.rows(0, 3))
            }
            RecordKind::CameraPoint { feature, camera } => {
                let pred = model.camera_jacobian(camera.as_deref(), p, kin, &r.q, s, feature, &mut self.work, &mut self.camera)?;
                // rows 2..5: the camera point
                (pred.measured_point, self.camera.rows(2, 3))
            }
        })
    }
}

impl Problem for PointResiduals<'_, '_> {
    fn residual_count(&self) -> usize {
        3 * self.records.len()
    }
    fn parameter_count(&self) -> usize {
        self.model.param_count()
    }
    fn residuals(&self, x: &[f64], residuals: &mut [f64]) -> Result<(), NotEvaluable> {
        self.evaluate(x, residuals, None)
    }
    fn residuals_and_jacobian(&self, x: &[f64], residuals: &mut [f64], jacobian: &mut DMatrix<f64>) -> Result<(), NotEvaluable> {
        self.evaluate(x, residuals, Some(jacobian))
    }
}
