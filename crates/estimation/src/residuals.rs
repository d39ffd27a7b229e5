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
//! ([`ForwardModel::tracker_point_jacobian_mapped`]: the reported point's rows,
//! [`ForwardModel::probe_jacobian`], [`ForwardModel::camera_jacobian`] rows of the camera point),
//! negated and whitened. Records are evaluated in parallel chunks (crate `record_chunks`), with
//! results identical bit for bit to a sequential pass. Where the model's sighted point is linear
//! in its parameters (every machine term a geometric series or squareness on a cartesian or
//! five-axis machine: `metrocell_model::linear_target`), each tracker point's P₀ and
//! A = ∂P/∂p are formed at the first evaluation and kept, so every later one is a product
//! instead of the terms' series and levers (equal to the full evaluation to round-off; test).

use std::sync::Mutex;

use metrocell_model::{
    ForwardModel, KeptLayout, KinematicTruth, Workspace, CAMERA_ROWS, PROBE_ROWS,
};
use metrocell_physics::{PhysicsError, Signals};
use metrocell_solver::{zeroed_matrix, NotEvaluable, Problem};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::record_chunks::{self, Chunk, DisjointRows};
use crate::records::{MeasurementRecord, RecordKind};

/// Measurement records (points, probe hits, camera points) against the model.
pub struct PointResiduals<'m, 'a> {
    model: &'m ForwardModel<'a>,
    records: &'m [MeasurementRecord],
    /// L⁻¹ of each record's covariance.
    whitening: Vec<Matrix3<f64>>,
    /// L of each record's covariance (Σ = L·Lᵀ), to turn whitened residuals back into metres.
    colouring: Vec<Matrix3<f64>>,
    /// The records' chunks, each with its own scratch: one per worker thread.
    chunks: Vec<Mutex<Chunk<Scratch>>>,
}

/// What evaluating a chunk's records writes into: the signals the model fills per record, and
/// the Jacobian buffers; and, where the model's sighted point is linear in its parameters
/// (`metrocell_model::linear_target`), each tracker point's P₀ and A, kept from the first
/// evaluation on (the records and the model do not change).
struct Scratch {
    signals: Vec<Signals>,
    buffers: Buffers,
    kept: Option<Kept>,
    /// The Jacobian rows of [`BLOCK_RECORDS`] records, column-major ([`BLOCK_ROWS`] per
    /// column), before they go to the m × n Jacobian.
    block: Vec<f64>,
}

/// Records whose Jacobian rows are gathered before they are written out: a record's own three
/// rows, written to the n columns of an m × n column-major matrix one record at a time, touch n
/// cache lines apiece, and those stores were the evaluation's hot spot in the profile; 8
/// records make three whole lines per column (free-column evaluation on one core: 8.9–9.4 ms
/// before, 7.5–8.6 ms after, in runs minutes apart).
const BLOCK_RECORDS: usize = 8;
const BLOCK_ROWS: usize = 3 * BLOCK_RECORDS;

/// The chunk's tracker points' P₀ and A packed by `layout`: the chunk's k-th record in column k
/// of `values` (zero for a record that is not a tracker point).
struct Kept {
    layout: KeptLayout,
    values: DMatrix<f64>,
}

impl Kept {
    fn of(&self, k: usize) -> &[f64] {
        let len = self.layout.values_per_reading();
        &self.values.as_slice()[len * k..len * (k + 1)]
    }
}

impl Scratch {
    /// Form the kept targets of the chunk's records (`records`, the first of which is record
    /// `start`) on first use, where the model's target is linear (tracker points only; the
    /// other kinds are evaluated in full). The layout holds the rows any reading of the chunk
    /// needs: it starts from the first reading's and, should a later reading need a row more
    /// (a lever that was zero), is widened and the chunk packed again.
    fn keep_targets(
        &mut self,
        model: &ForwardModel,
        records: &[MeasurementRecord],
        start: usize,
    ) -> Result<(), EvaluationFailure> {
        let (Some(columns), Some(len), None) = (
            model.linear_target_columns(),
            model.linear_target_len(),
            &self.kept,
        ) else {
            return Ok(());
        };
        let mut full = vec![0.0; len];
        let mut layout = KeptLayout::empty(columns);
        // a column for every record, so that any record's slice exists (only points use theirs)
        let mut values = zeroed_matrix(layout.values_per_reading(), records.len());
        'pack: loop {
            for (k, (r, s)) in records.iter().zip(&mut self.signals).enumerate() {
                if r.kind != RecordKind::Point {
                    continue;
                }
                model
                    .linear_target(&r.q, s, &mut self.buffers.work, &mut full)
                    .map_err(|error| EvaluationFailure::Record {
                        index: start + k,
                        error,
                    })?;
                if !layout.covers(&full) {
                    layout = layout.widened(&full);
                    values = zeroed_matrix(layout.values_per_reading(), records.len());
                    if k > 0 {
                        continue 'pack;
                    }
                }
                layout.pack(&full, values.column_mut(k).as_mut_slice());
            }
            break;
        }
        self.kept = Some(Kept { layout, values });
        Ok(())
    }
}

/// Why a model evaluation over the records failed: the model itself (e.g. its kinematics at
/// these parameters), or one record (its index and the error).
#[derive(Debug)]
pub enum EvaluationFailure {
    Model(PhysicsError),
    Record { index: usize, error: PhysicsError },
}

impl From<EvaluationFailure> for PhysicsError {
    fn from(f: EvaluationFailure) -> Self {
        match f {
            EvaluationFailure::Model(e) | EvaluationFailure::Record { error: e, .. } => e,
        }
    }
}

/// A record that cannot be used: its covariance is not positive definite or not finite.
#[derive(Debug, Clone, PartialEq)]
pub struct BadCovariance {
    pub index: usize,
    pub point_id: String,
}

/// L⁻¹ with Σ = L·Lᵀ, or None if Σ is not finite and positive definite.
pub fn whitening(covariance: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    cholesky_factors(covariance).map(|(_, inverse)| inverse)
}

/// L and L⁻¹ with Σ = L·Lᵀ (one factorisation), or None if Σ is not finite and positive definite.
fn cholesky_factors(covariance: &Matrix3<f64>) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    if !covariance.iter().all(|v| v.is_finite()) {
        return None;
    }
    let l = covariance.cholesky()?.l();
    Some((l, l.try_inverse()?))
}

impl<'m, 'a> PointResiduals<'m, 'a> {
    pub fn new(
        model: &'m ForwardModel<'a>,
        records: &'m [MeasurementRecord],
    ) -> Result<Self, BadCovariance> {
        let (colouring, whitening) = records
            .iter()
            .enumerate()
            .map(|(index, r)| {
                cholesky_factors(&r.covariance).ok_or_else(|| BadCovariance {
                    index,
                    point_id: r.point_id.clone(),
                })
            })
            .collect::<Result<(Vec<_>, Vec<_>), _>>()?;
        let chunks = record_chunks::split(records.len(), |start, len| Scratch {
            signals: records[start..start + len]
                .iter()
                .map(|r| r.signals.clone())
                .collect(),
            buffers: Buffers::new(model),
            kept: None,
            block: vec![0.0; BLOCK_ROWS * model.param_count()],
        });
        Ok(Self {
            model,
            records,
            whitening,
            colouring,
            chunks,
        })
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
        Ok(self.predictions_of_records(p)?)
    }

    /// [`Self::predictions`], naming the first record that cannot be predicted by its index.
    pub fn predictions_of_records(
        &self,
        p: &[f64],
    ) -> Result<Vec<Vector3<f64>>, EvaluationFailure> {
        let kin = self
            .model
            .kinematic_truth(p)
            .map_err(EvaluationFailure::Model)?;
        let mut out = vec![Vector3::zeros(); self.records.len()];
        let outs = record_chunks::shares(&self.chunks, &mut out, 1);
        record_chunks::for_each(&self.chunks, outs, |c, out: &mut [Vector3<f64>]| {
            let records = &self.records[c.start..c.start + c.len];
            c.scratch.keep_targets(self.model, records, c.start)?;
            let Scratch {
                signals,
                buffers,
                kept,
                ..
            } = &mut c.scratch;
            for (k, (o, s)) in out.iter_mut().zip(signals.iter_mut()).enumerate() {
                let i = c.start + k;
                let r = &records[k];
                *o = match (kept.as_ref(), &r.kind) {
                    (Some(kept), RecordKind::Point) => self
                        .model
                        .tracker_linear(None, p, &kept.layout, kept.of(k), s, &mut buffers.work)
                        .map(|t| t.measured_point()),
                    _ => predict(self.model, p, &kin, r, s),
                }
                .map_err(|error| EvaluationFailure::Record { index: i, error })?;
            }
            Ok(())
        })?;
        Ok(out)
    }

    /// measured − predicted of every record at `p`, m (unwhitened).
    pub fn raw_residuals(&self, p: &[f64]) -> Result<Vec<Vector3<f64>>, PhysicsError> {
        Ok(self
            .predictions(p)?
            .iter()
            .zip(self.records)
            .map(|(pred, r)| r.measured - pred)
            .collect())
    }

    /// Whitened residuals (3 per record, as [`Problem::residuals`] writes them) back in metres:
    /// measured − predicted of each record, L·z.
    pub fn unwhitened(&self, z: &[f64]) -> Vec<Vector3<f64>> {
        assert_eq!(
            z.len(),
            3 * self.records.len(),
            "3 whitened residuals per record"
        );
        self.colouring
            .iter()
            .zip(z.chunks_exact(3))
            .map(|(l, z)| l * Vector3::new(z[0], z[1], z[2]))
            .collect()
    }

    /// The Jacobian of the predictions w.r.t. the stacked parameters (3·records × n,
    /// unwhitened, rows x y z of each record in turn) at `p`.
    pub fn prediction_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, PhysicsError> {
        let n = self.model.param_count();
        let mut out = DMatrix::zeros(3 * self.records.len(), n);
        self.evaluate_rows(p, None, &mut out, &(0..n).collect::<Vec<_>>())?;
        Ok(out)
    }

    /// For every record i, rows 3i..3i+3 of `jac` in the given `columns` (the others are left
    /// as they are): without `residuals`, the prediction's Jacobian; with them, the residuals'
    /// −L⁻¹·∂prediction/∂p, and L⁻¹·(measured − predicted) into entries 3i..3i+3 of
    /// `residuals`.
    fn evaluate_rows(
        &self,
        p: &[f64],
        residuals: Option<&mut [f64]>,
        jac: &mut DMatrix<f64>,
        columns: &[usize],
    ) -> Result<(), EvaluationFailure> {
        let whiten = residuals.is_some();
        let kin = self
            .model
            .kinematic_truth(p)
            .map_err(EvaluationFailure::Model)?;
        let n = self.model.param_count();
        assert_eq!(jac.shape(), (3 * self.records.len(), n), "Jacobian shape");
        let target = DisjointRows::new(jac);
        let outs: Vec<Option<&mut [f64]>> = match residuals {
            Some(r) => record_chunks::shares(&self.chunks, r, 3)
                .into_iter()
                .map(Some)
                .collect(),
            None => self.chunks.iter().map(|_| None).collect(),
        };
        record_chunks::for_each(&self.chunks, outs, |c, mut out: Option<&mut [f64]>| {
            c.scratch
                .keep_targets(self.model, &self.records[c.start..c.start + c.len], c.start)?;
            let Scratch {
                signals,
                buffers,
                kept,
                block,
            } = &mut c.scratch;
            for (k, s) in signals.iter_mut().enumerate() {
                let i = c.start + k;
                let r = &self.records[i];
                // ∂r/∂p = −L⁻¹·∂prediction/∂p, column by column in fixed-size arithmetic,
                // into the block's rows of record i (the identity when not whitening)
                let w = if whiten {
                    -self.whitening[i]
                } else {
                    Matrix3::identity()
                };
                let b = k % BLOCK_RECORDS;
                let write = |c: usize, column: Vector3<f64>| {
                    block[c * BLOCK_ROWS + 3 * b..c * BLOCK_ROWS + 3 * b + 3]
                        .copy_from_slice(column.as_slice())
                };
                let kept = kept.as_ref().map(|kept| (&kept.layout, kept.of(k)));
                let pred = buffers
                    .predict_with_jacobian(self.model, p, &kin, r, s, kept, &w, columns, write)
                    .map_err(|error| EvaluationFailure::Record { index: i, error })?;
                if let Some(out) = out.as_deref_mut() {
                    let z = self.whitening[i] * (r.measured - pred);
                    out[3 * k..3 * k + 3].copy_from_slice(z.as_slice());
                }
                if b + 1 == BLOCK_RECORDS || k + 1 == c.len {
                    // the block's records into J, each column's rows in one contiguous write
                    let first = k - b;
                    for &col in columns {
                        // SAFETY: rows 3·first..3(k+1) belong to this chunk's records
                        unsafe {
                            target.set_rows(
                                3 * (c.start + first),
                                col,
                                &block[col * BLOCK_ROWS..col * BLOCK_ROWS + 3 * (b + 1)],
                            )
                        };
                    }
                }
            }
            Ok(())
        })
    }

    /// Residuals at `p` into `residuals` and, with `jac`, the Jacobian's columns k with
    /// `wanted[k]` (every column without `wanted`).
    fn evaluate(
        &self,
        p: &[f64],
        residuals: &mut [f64],
        jac: Option<&mut DMatrix<f64>>,
        wanted: Option<&[bool]>,
    ) -> Result<(), NotEvaluable> {
        let fail = |f: EvaluationFailure| match f {
            EvaluationFailure::Model(e) => NotEvaluable(e.to_string()),
            EvaluationFailure::Record { index, error } => NotEvaluable(format!(
                "record {index} ({}): {error}",
                self.records[index].point_id
            )),
        };
        match jac {
            // ∂r/∂p = −L⁻¹·∂prediction/∂p
            Some(j) => {
                let columns: Vec<usize> = (0..j.ncols())
                    .filter(|&k| wanted.is_none_or(|w| w[k]))
                    .collect();
                self.evaluate_rows(p, Some(&mut *residuals), j, &columns)
                    .map_err(fail)?
            }
            None => {
                let predicted = self.predictions_of_records(p).map_err(fail)?;
                for (i, (r, pred)) in self.records.iter().zip(&predicted).enumerate() {
                    let z = self.whitening[i] * (r.measured - pred);
                    residuals[3 * i..3 * i + 3].copy_from_slice(z.as_slice());
                }
            }
        }
        if let Some(i) = residuals.iter().position(|v| !v.is_finite()) {
            return Err(NotEvaluable(format!(
                "record {} ({}): residual not finite",
                i / 3,
                self.records[i / 3].point_id
            )));
        }
        Ok(())
    }
}

/// The model's prediction of record `r` at `p` (signals `s`), in the record's frame: a point
/// through the tracker, a probe hit through its probe, a camera point through its camera.
pub fn predict(
    model: &ForwardModel,
    p: &[f64],
    kin: &KinematicTruth,
    r: &MeasurementRecord,
    s: &mut Signals,
) -> Result<Vector3<f64>, PhysicsError> {
    match &r.kind {
        RecordKind::Point => {
            let tool = model.tool_state(p, kin, &r.q, s, None)?;
            Ok(model.tracker(p, &tool, s)?.measured_point())
        }
        RecordKind::ProbeHit { target, probe } => Ok(model
            .probe_hit(probe.as_deref(), p, kin, &r.q, s, target)?
            .centre),
        RecordKind::CameraPoint { feature, camera } => {
            let tool = model.tool_state(p, kin, &r.q, s, None)?;
            Ok(model
                .camera(camera.as_deref(), p, &tool, s, feature)?
                .measured_point)
        }
        RecordKind::Reference { nest } => Ok(model
            .tracker_of_fixed_point(None, p, known_nest(r, nest)?, s)?
            .measured_point()),
    }
}

/// A reference record's nest, or an error saying it must be estimated first.
fn known_nest(r: &MeasurementRecord, nest: &Vector3<f64>) -> Result<Vector3<f64>, PhysicsError> {
    if nest.iter().all(|v| v.is_finite()) {
        Ok(*nest)
    } else {
        Err(PhysicsError::InvalidInput { what: format!("reference record `{}`", r.point_id), reason: "its nest's position is not known yet (estimate it from its readings first: estimation `estimate_nests`)".into() })
    }
}

/// The model's Jacobian buffers: its workspace, and one for each reading kind that is not a
/// tracker's (allocated once per problem).
struct Buffers {
    work: Workspace,
    probe: DMatrix<f64>,
    camera: DMatrix<f64>,
}

impl Buffers {
    fn new(model: &ForwardModel) -> Self {
        let n = model.param_count();
        Self {
            work: Workspace::new(model),
            probe: DMatrix::zeros(PROBE_ROWS, n),
            camera: DMatrix::zeros(CAMERA_ROWS, n),
        }
    }

    /// [`predict`] (bit for bit; with a tracker point's `kept` target, as the model's
    /// `tracker_linear`), and `write(c, map·column c of its Jacobian)` for each of `columns`. A
    /// tracker's point goes straight from the model's chain to `write`; the other kinds through
    /// their buffer.
    #[allow(clippy::too_many_arguments)]
    fn predict_with_jacobian(
        &mut self,
        model: &ForwardModel,
        p: &[f64],
        kin: &KinematicTruth,
        r: &MeasurementRecord,
        s: &mut Signals,
        kept: Option<(&KeptLayout, &[f64])>,
        map: &Matrix3<f64>,
        columns: &[usize],
        mut write: impl FnMut(usize, Vector3<f64>),
    ) -> Result<Vector3<f64>, PhysicsError> {
        let (pred, rows) = match &r.kind {
            RecordKind::Point => {
                let reading = match kept {
                    Some((layout, kept)) => model.tracker_point_jacobian_mapped_linear(
                        None,
                        p,
                        layout,
                        kept,
                        s,
                        &mut self.work,
                        map,
                        columns,
                        write,
                    )?,
                    None => model.tracker_point_jacobian_mapped(
                        None,
                        p,
                        kin,
                        &r.q,
                        s,
                        &mut self.work,
                        map,
                        columns,
                        write,
                    )?,
                };
                return Ok(reading.measured_point());
            }
            RecordKind::ProbeHit { target, probe } => {
                let pred = model.probe_jacobian(
                    probe.as_deref(),
                    p,
                    kin,
                    &r.q,
                    s,
                    target,
                    &mut self.work,
                    &mut self.probe,
                )?;
                (pred.centre, self.probe.rows(0, 3))
            }
            RecordKind::CameraPoint { feature, camera } => {
                let pred = model.camera_jacobian(
                    camera.as_deref(),
                    p,
                    kin,
                    &r.q,
                    s,
                    feature,
                    &mut self.work,
                    &mut self.camera,
                )?;
                // rows 2..5: the camera point
                (pred.measured_point, self.camera.rows(2, 3))
            }
            RecordKind::Reference { nest } => {
                return Ok(model
                    .tracker_point_jacobian_of_fixed_point_mapped(
                        None,
                        p,
                        known_nest(r, nest)?,
                        s,
                        &mut self.work,
                        map,
                        columns,
                        write,
                    )?
                    .measured_point());
            }
        };
        for &c in columns {
            write(c, map * rows.fixed_view::<3, 1>(0, c));
        }
        Ok(pred)
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
        self.evaluate(x, residuals, None, None)
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        self.evaluate(x, residuals, Some(jacobian), None)
    }
    /// The unwanted columns are not written: with many records, storing the Jacobian is a
    /// memory-bound share of an evaluation.
    fn residuals_and_jacobian_of(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: &mut DMatrix<f64>,
        wanted: &[bool],
    ) -> Result<(), NotEvaluable> {
        assert_eq!(
            wanted.len(),
            jacobian.ncols(),
            "one wanted flag per parameter"
        );
        self.evaluate(x, residuals, Some(jacobian), Some(wanted))
    }
}
