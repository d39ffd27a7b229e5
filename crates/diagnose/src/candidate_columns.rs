//! Jacobian columns of a candidate term from the shared forward model, at the declared fit:
//! how each record's predicted reading moves per unit of each of the candidate's parameters,
//! whitened by the record's covariance like its residual.
//!
//! Two routes to the same numbers (the second is the first's chain rule; no test compares them
//! yet):
//! * the model with the candidate added — the estimator's prediction Jacobian of the augmented
//!   model (each record kind through its own instrument), the candidate's columns — for
//!   records that are not all tracker points, instrument terms (warm-up, refraction), kinematic
//!   terms (delta, arm), workpiece-frame terms (they move the part, not the tool) and every
//!   term on an arm (whose tool frame turns);
//! * for machine- and tool-frame displacement terms on cartesian, delta and five-axis machines,
//!   the same chain taken in two pieces: ∂reading/∂d (3 × 3 per record, the columns of a
//!   `tool_offset` added to the model — a displacement d of the tool point in the machine frame,
//!   which is what every such term produces), times the term's own analytic ∂d/∂θ. The first
//!   piece is computed once per record; each candidate variant then costs one term evaluation
//!   per record instead of a pass through the whole model.

use metrocell_estimation::{MeasurementRecord, PointResiduals, RecordKind};
use metrocell_model::{ForwardModel, MachineKinematics};
use metrocell_physics::model::TermModel;
use metrocell_physics::{
    configure, ConfiguredTerm, EffectKind, Frame, PhysicsError, Signals, TermConfig,
};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::candidates::Placement;

/// A candidate's whitened columns (3 rows per record) for all its parameters.
#[derive(Debug, Clone)]
pub struct TermColumns {
    pub term: ConfiguredTerm,
    pub columns: DMatrix<f64>,
}

/// Everything the columns are computed from: the declared model at its fit, the records with
/// their whitening, and the per-record sensitivity of the reading to a machine displacement.
pub struct ColumnContext<'m, 'a> {
    model: &'m ForwardModel<'a>,
    x: Vec<f64>,
    records: &'m [MeasurementRecord],
    whitening: &'m [Matrix3<f64>],
    signals: Vec<Signals>,
    /// ∂(reported point)/∂(machine-frame displacement of the tool point), per record; None on
    /// an arm.
    sensitivity: Option<Vec<Matrix3<f64>>>,
    /// Nominal point in the machine frame that machine-frame terms are evaluated at.
    machine_points: Vec<Vector3<f64>>,
}

fn tool_offset_term() -> ConfiguredTerm {
    configure(&TermConfig {
        id: "tool_offset".into(),
        use_defaults: true,
        ..Default::default()
    })
    .expect("tool_offset builds with defaults")
}

/// The stacked vector of a model with `extra` inserted at `at`.
fn with_inserted(x: &[f64], at: usize, extra: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len() + extra.len());
    out.extend_from_slice(&x[..at]);
    out.extend_from_slice(extra);
    out.extend_from_slice(&x[at..]);
    out
}

impl<'m, 'a> ColumnContext<'m, 'a> {
    /// `x` is the declared fit (the model's stacked order), `whitening` L⁻¹ of each record.
    pub fn new(
        model: &'m ForwardModel<'a>,
        x: &[f64],
        records: &'m [MeasurementRecord],
        whitening: &'m [Matrix3<f64>],
    ) -> Result<Self, PhysicsError> {
        let signals: Vec<Signals> = records.iter().map(|r| r.signals.clone()).collect();
        // (a reference nest has no joints, and no machine term acts on it)
        let machine_points: Vec<Vector3<f64>> = records
            .iter()
            .map(|r| {
                if r.q.len() >= 3 {
                    model
                        .nominal_machine_point(&r.q, &r.signals)
                        .unwrap_or_else(Vector3::zeros)
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        let mut ctx = Self {
            model,
            x: x.to_vec(),
            records,
            whitening,
            signals,
            sensitivity: None,
            machine_points,
        };
        // ∂reading/∂d from a tool offset's columns is the tracker's: chaining through it is for
        // point records only (probe and camera records take the full augmented Jacobian)
        let points_only = records
            .iter()
            .all(|r| matches!(r.kind, RecordKind::Point | RecordKind::Reference { .. }));
        if points_only && !matches!(model.machine.kinematics, MachineKinematics::SerialArm(_)) {
            // ∂reading/∂d: the columns of a tool offset (declared, or added at zero)
            let names = model.param_names();
            let sens = match names.iter().position(|n| n == "tool_offset.dx") {
                Some(at) => ctx.jacobian_columns(model, &ctx.x.clone(), at, 3)?,
                None => {
                    let term = tool_offset_term();

                    ctx.augmented_columns(&term, Placement::Machine)?
                }
            };
            ctx.sensitivity = Some(
                (0..records.len())
                    .map(|i| sens.fixed_view::<3, 3>(3 * i, 0).into_owned())
                    .collect(),
            );
        }
        Ok(ctx)
    }

    pub fn records(&self) -> &[MeasurementRecord] {
        self.records
    }

    /// Unwhitened columns `start..start + len` of `model`'s reading Jacobian at `x`, 3 rows per
    /// record: the estimator's own prediction Jacobian, so each record kind (tracker point,
    /// probe hit, camera point) gets its own instrument's derivatives.
    fn jacobian_columns(
        &mut self,
        model: &ForwardModel,
        x: &[f64],
        start: usize,
        len: usize,
    ) -> Result<DMatrix<f64>, PhysicsError> {
        let problem =
            PointResiduals::new(model, self.records).map_err(|e| PhysicsError::BadValue {
                term: "records".into(),
                key: "covariance".into(),
                text: e.point_id.clone(),
                reason: format!(
                    "record {} has a covariance that is not finite and positive definite",
                    e.index
                ),
            })?;
        Ok(problem
            .prediction_jacobian(x)?
            .columns(start, len)
            .into_owned())
    }

    /// Unwhitened columns of `term` (at its configured parameters) through the model with it
    /// added.
    fn augmented_columns(
        &mut self,
        term: &ConfiguredTerm,
        placement: Placement,
    ) -> Result<DMatrix<f64>, PhysicsError> {
        let mut machine: TermModel = self.model.machine_terms.clone();
        let mut instruments: TermModel = self.model.instrument_terms.clone();
        let n_machine = machine.params().len();
        let at = match placement {
            Placement::Machine => {
                machine.push(term.clone())?;
                n_machine
            }
            Placement::Instrument => {
                instruments.push(term.clone())?;
                self.x.len()
            }
        };
        let augmented = ForwardModel::new(self.model.machine, &machine, &instruments)?;
        let x = with_inserted(&self.x, at, &term.params);
        let len = term.params.len();
        self.jacobian_columns(&augmented, &x, at, len)
    }

    /// The whitened columns of a candidate term given by its config (parameters at the
    /// config's values).
    pub fn columns(
        &mut self,
        config: &TermConfig,
        placement: Placement,
    ) -> Result<TermColumns, PhysicsError> {
        let term = configure(config)?;
        let chain = placement == Placement::Machine
            && matches!(
                term.term.effect(),
                EffectKind::Displacement(Frame::Machine | Frame::Tool)
            )
            && self.sensitivity.is_some();
        let raw = if chain {
            self.chained_columns(&term)?
        } else {
            self.augmented_columns(&term, placement)?
        };
        let mut columns = raw;
        for i in 0..self.records.len() {
            let w = self.whitening[i];
            let block = w * columns.rows(3 * i, 3);
            columns.rows_mut(3 * i, 3).copy_from(&block);
        }
        Ok(TermColumns { term, columns })
    }

    /// ∂reading/∂d · ∂d/∂θ, unwhitened.
    fn chained_columns(&mut self, term: &ConfiguredTerm) -> Result<DMatrix<f64>, PhysicsError> {
        let sens = self.sensitivity.as_ref().expect("checked by the caller");
        let k = term.params.len();
        let mut out = DMatrix::zeros(3 * self.records.len(), k);
        let mut value = [0.0; 3];
        let mut jac = DMatrix::zeros(3, k);
        let reads_point = term
            .term
            .signals()
            .contains(&metrocell_physics::SignalKind::MachinePoint);
        for i in 0..self.records.len() {
            if matches!(self.records[i].kind, RecordKind::Reference { .. }) {
                // the machine does not move a reference nest: its rows stay zero
                continue;
            }
            let s = &mut self.signals[i];
            if reads_point {
                s.machine_point = Some(self.machine_points[i]);
            }
            term.term
                .evaluate_into(&term.params, s, &mut value, jac.columns_mut(0, k))?;
            out.view_mut((3 * i, 0), (3, k))
                .copy_from(&(sens[i] * &jac));
        }
        Ok(out)
    }

    /// Whitened columns of the declared model's parameters `indices` at the declared fit.
    pub fn declared_columns(&mut self, indices: &[usize]) -> Result<DMatrix<f64>, PhysicsError> {
        let n = self.model.param_count();
        let full = {
            let x = self.x.clone();
            let model = self.model;
            self.jacobian_columns(model, &x, 0, n)?
        };
        let mut out = DMatrix::zeros(full.nrows(), indices.len());
        for (j, &c) in indices.iter().enumerate() {
            out.set_column(j, &full.column(c));
        }
        for i in 0..self.records.len() {
            let block = self.whitening[i] * out.rows(3 * i, 3);
            out.rows_mut(3 * i, 3).copy_from(&block);
        }
        Ok(out)
    }

    /// The per-record sensitivity of the reading to a machine-frame displacement, if the family
    /// has one (empirical corrections use it).
    pub fn sensitivity(&self) -> Option<&[Matrix3<f64>]> {
        self.sensitivity.as_deref()
    }
}
