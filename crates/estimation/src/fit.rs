//! Batch identification: the declared model's free parameters fitted to measured points.
//!
//! What it does, in order:
//! 1. Frame: records in the machine frame fix the instrument pose at the identity; records in an
//!    instrument frame start the pose from a weighted Kabsch registration of the measured points
//!    to the model's tool points (crates/kinematics `rigid_registration`), so an export in any tracker
//!    placement converges, and leave it free unless the model file fixes it.
//! 2. Levenberg–Marquardt (crates/solver) on [`PointResiduals`], bounded by each parameter's
//!    documented range, with the model file's priors, a robust loss if asked (outliers that
//!    slipped through are down-weighted and counted, not silently kept), and truncated-SVD steps
//!    so that combinations the data cannot separate stay at their start (minimum-norm solution
//!    on the identifiable subspace).
//! 3. Honest uncertainty: covariance (JᵀWJ)⁻¹ scaled by the a-posteriori variance factor σ̂₀²,
//!    standard uncertainties, correlations, and the identifiability analysis (rank, condition
//!    number, each unidentifiable combination in words).
//! 4. When the free parameters are not all identifiable, one parameter of each null direction
//!    is **held** at its start value (a machine-term parameter rather than the instrument pose,
//!    which then absorbs the combination) and the fit is repeated, so every other parameter
//!    gets an uncertainty. The held ones are named with the combination they take part in
//!    ([`Fit::held`]); their values are conventions, not estimates.
//!
//! Records whose measured point, joints or covariance are not finite are left out and named
//! ([`Fit::skipped`]); records the robust loss down-weighted are named too ([`Fit::outliers`]).

use metrocell_kinematics::rigid_registration::{register, Correspondence};
use metrocell_model::{ForwardModel, ParameterSetup};
use metrocell_physics::PhysicsError;
use metrocell_solver::identifiability::GRAM_RCOND;
use metrocell_solver::{
    normal_matrix, solve, solve_from, zeroed_matrix, Evaluated, Identifiability, Loss, NullSpace,
    Options, Prior, Problem, Solution, SolverError,
};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::records::{RecordFrame, RecordKind, RecordSet};
use crate::residuals::{EvaluationFailure, PointResiduals};

/// Settings of a batch fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Loss on the whitened residuals; Huber at 4σ keeps honest data quadratic (6e-5 of Gaussian components exceed it) and limits what
    /// an outlier can pull.
    pub loss: Loss,
    pub max_iterations: usize,
    /// Relative singular value (of the column-scaled Jacobian) below which a direction counts
    /// as unidentifiable: 1e-6, where the solver's covariance stops being computed (normal
    /// matrix eigenvalues below 1e-12 of the largest).
    pub rcond: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            loss: Loss::Huber(4.0),
            max_iterations: 100,
            rcond: 1e-6,
        }
    }
}

/// Why a fit could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("no usable measurements (every record was rejected or the recording has none)")]
    NoRecords,
    #[error(
        "record {index} (point `{point_id}`): its covariance is not finite and positive definite"
    )]
    BadCovariance { index: usize, point_id: String },
    #[error("{0}")]
    Model(#[from] PhysicsError),
    #[error("the instrument pose could not be registered from the points: {0}")]
    Registration(String),
    #[error("{0}")]
    Solver(#[from] SolverError),
    #[error("{needed} parameters are free but only {available} residuals: measure at least {points} points")]
    TooFew {
        needed: usize,
        available: usize,
        points: usize,
    },
    /// A record the model cannot predict (a signal a term needs is missing, a joint vector
    /// the kinematics cannot reach, …).
    #[error("record {index} (point `{point_id}`, t = {time} s): {source}{hint}")]
    Record {
        index: usize,
        point_id: String,
        time: f64,
        source: PhysicsError,
        hint: String,
    },
}

/// What to do about a missing signal, by the kind of signal.
fn missing_signal_hint(e: &PhysicsError) -> String {
    let PhysicsError::MissingSignal { signal, .. } = e else {
        return String::new();
    };
    let s = signal.to_lowercase();
    let source = if s.contains("temperature") && !s.contains("air") {
        "a `sensor_msgs/Temperature` topic `/temperature/<sensor>` for the sensor the term names (or a `temperature.<sensor>` column in a CSV import)"
    } else if s.contains("power") {
        "the instrument's power-on time (the tracker's power-on topic, or `instrument_on_time` in a CSV import)"
    } else if s.contains("air") {
        "the weather station's air temperature, pressure and humidity"
    } else if s.contains("load") {
        "the load force"
    } else {
        "the commanded joint states (`/machine/commanded_joint_states`) with velocities"
    };
    format!(". The recording does not carry it: record {source}, or take the term out of the model")
}

/// A parameter held at its start value because the data cannot separate it from others.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldParameter {
    /// Index in the stacked vector, and `label.param`.
    pub index: usize,
    pub name: String,
    /// The combination in words ("a and b are not separable: a − 0.5·b").
    pub combination: String,
}

/// A record left out of the fit, or down-weighted by it.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordNote {
    /// Index in the record set.
    pub index: usize,
    pub point_id: String,
    pub time: f64,
    pub reason: String,
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterEstimate {
    /// `label.param`.
    pub name: String,
    pub value: f64,
    /// Standard uncertainty (k = 1), None if fixed or not identifiable.
    pub sigma: Option<f64>,
    pub unit: &'static str,
    pub free: bool,
    /// The physically possible range (the fit's bounds; ±∞ where the quantity has none).
    pub range: (f64, f64),
    /// The usual range (what real machines show): for the words, never a limit.
    pub usual: (f64, f64),
    /// Set when the fit ended on a bound of the possible range: the data want a value beyond
    /// it, and `sigma` is then no interior uncertainty (it describes the bounded solution).
    pub at_bound: Option<BoundSide>,
}

/// Which bound of its possible range a parameter ended on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundSide {
    Lower,
    Upper,
}

impl BoundSide {
    pub fn name(self) -> &'static str {
        match self {
            BoundSide::Lower => "lower",
            BoundSide::Upper => "upper",
        }
    }
}

impl ParameterEstimate {
    /// "`name` = v ± σ unit", or for a parameter at a bound "`name` = v unit (at its lower bound
    /// of the possible range: the data want a smaller value; no interior σ)".
    pub fn describe(&self) -> String {
        match self.at_bound {
            None => format!("{} = {}", self.name, crate::fit_summary::value_with_sigma(self.value, self.sigma, self.unit)),
            Some(side) => format!(
                "{} = {} — at the {} bound of its possible range: the data want a {} value, and no interior σ can be given",
                self.name,
                crate::fit_summary::value_with_sigma(self.value, None, self.unit),
                side.name(),
                if side == BoundSide::Lower { "smaller" } else { "larger" }
            ),
        }
    }
}

/// The result of [`fit`].
#[derive(Debug, Clone)]
pub struct Fit {
    pub parameters: Vec<ParameterEstimate>,
    /// The stacked parameter vector at the solution (the model's order).
    pub x: Vec<f64>,
    /// Scaled covariance of the stacked vector (zero for fixed), None if not all free
    /// parameters are identifiable.
    pub covariance: Option<DMatrix<f64>>,
    /// measured − predicted at the start and at the solution, m.
    pub residuals_before: Vec<Vector3<f64>>,
    pub residuals_after: Vec<Vector3<f64>>,
    /// χ² of the whitened residuals per degree of freedom at the solution.
    pub chi2_per_dof: f64,
    pub identifiability: Identifiability,
    /// Whitened residual components the robust loss down-weighted (outliers), of 3 per record.
    pub downweighted: usize,
    /// Records with a component beyond the robust loss's threshold at the solution.
    pub outliers: Vec<RecordNote>,
    /// Records left out because a value was not finite (never silently).
    pub skipped: Vec<RecordNote>,
    /// Parameters held at their start to make the rest identifiable (empty when all are).
    pub held: Vec<HeldParameter>,
    /// Identifiability of the declared free parameters at the start (before holding any).
    pub declared_identifiability: Identifiability,
    /// Records used (after skipping).
    pub used: Vec<usize>,
    /// The robust loss's threshold (σ), None for plain least squares.
    pub options_threshold: Option<f64>,
    pub solution: Solution,
}

impl Fit {
    pub fn parameter(&self, name: &str) -> Option<&ParameterEstimate> {
        self.parameters.iter().find(|p| p.name == name)
    }
}

/// The bound a value sits on (within 1e-9 of the parameter's typical size), if any.
fn bound_reached(value: f64, lower: f64, upper: f64, typical: f64) -> Option<BoundSide> {
    let tol = 1e-9 * typical.max(value.abs());
    if lower.is_finite() && value - lower <= tol {
        Some(BoundSide::Lower)
    } else if upper.is_finite() && upper - value <= tol {
        Some(BoundSide::Upper)
    } else {
        None
    }
}

/// RMS of the 3-D residual vectors (per coordinate), m.
pub fn rms(residuals: &[Vector3<f64>]) -> f64 {
    if residuals.is_empty() {
        return 0.0;
    }
    (residuals.iter().map(|r| r.norm_squared()).sum::<f64>() / (3 * residuals.len()) as f64).sqrt()
}

/// The start vector: the model's configured parameters, with the instrument pose set for the
/// frame of the records (identity in the machine frame, registered in an instrument frame
/// unless the setup fixes it).
pub fn start_vector(
    model: &ForwardModel,
    setup: &ParameterSetup,
    records: &RecordSet,
) -> Result<Vec<f64>, FitError> {
    let mut x = model.params();
    // every pose: the instrument's only one, or one per placement (`tracker_pose[<setup>]`)
    let poses = model.pose_param_starts();
    let several = poses.iter().any(|(s, _)| s.is_some());
    for (placement, pose) in poses {
        match &records.frame {
            RecordFrame::Machine => x[pose..pose + 6].iter_mut().for_each(|v| *v = 0.0),
            RecordFrame::Instrument(_) if setup.free[pose..pose + 6].iter().any(|f| *f) => {
                let kin = model.kinematic_truth(&x)?;
                let mut pairs = Vec::with_capacity(records.len());
                // the tracker's points of this placement (probe hits and camera points are in
                // frames of their own)
                let mine = |r: &&crate::records::MeasurementRecord| {
                    !several || r.signals.setup.as_deref() == placement.as_deref()
                };
                for r in records
                    .records
                    .iter()
                    .filter(|r| r.kind == RecordKind::Point)
                    .filter(mine)
                {
                    let mut s = r.signals.clone();
                    let tool = model.tool_state(&x, &kin, &r.q, &mut s, None)?;
                    pairs.push(Correspondence {
                        tracker: r.measured,
                        tracker_covariance: r.covariance,
                        machine: tool.target(),
                        machine_covariance: Matrix3::identity() * 1e-12,
                    });
                }
                if several && pairs.len() < 3 {
                    // a placement without three points keeps its start (the caller names it)
                    continue;
                }
                let reg = register(&pairs).map_err(|e| {
                    FitError::Registration(match &placement {
                        Some(s) => format!("setup `{s}`: {e}"),
                        None => e.to_string(),
                    })
                })?;
                let p = metrocell_model::InstrumentPose::from_rotation(
                    reg.translation,
                    reg.rotation.matrix(),
                );
                x[pose..pose + 6].copy_from_slice(&p.term_params());
            }
            RecordFrame::Instrument(_) => {}
        }
    }
    Ok(x)
}

/// Fit the free parameters of `setup` to `records` from `start` (None: [`start_vector`]).
///
/// In order: the usable records (the others named), the free parameters (the pose is held in
/// the machine frame) and whether the readings are enough, the start, the bounds and priors,
/// what the design identifies at the start (parameters it cannot separate held), the fit, more
/// parameters held until the rest is identifiable at the solution, the estimates and the
/// records beyond the robust loss's threshold.
pub fn fit(
    model: &ForwardModel,
    setup: &ParameterSetup,
    records: &RecordSet,
    start: Option<Vec<f64>>,
    options: &FitOptions,
) -> Result<Fit, FitError> {
    let (skipped, used) = usable_records(records);
    // the records themselves when all are usable (a copy of 10⁴ records and their signals is
    // milliseconds of a fit that takes tens)
    let subset;
    let kept: &RecordSet = if skipped.is_empty() {
        records
    } else {
        subset = RecordSet {
            check: Vec::new(),
            frame: records.frame.clone(),
            records: used.iter().map(|&i| records.records[i].clone()).collect(),
            rejected: vec![],
            sources: vec![],
        };
        &subset
    };
    if kept.is_empty() {
        return Err(FitError::NoRecords);
    }
    let mut free = free_parameters(model, setup, kept);
    let n_free = enough_readings(setup, &free, kept.len())?;
    let problem =
        PointResiduals::new(model, &kept.records).map_err(|b| FitError::BadCovariance {
            index: used[b.index],
            point_id: b.point_id,
        })?;
    // a record the model cannot predict is looked for only once the start or its evaluation
    // has failed: a search of its own costs a pass over every record
    let unpredictable = || unpredictable_record(model, &problem, kept, &used);
    let x0 = match start {
        Some(x) => x,
        None => start_vector(model, setup, kept).map_err(|e| unpredictable().unwrap_or(e))?,
    };
    let names = model.param_names();
    let solving = Solving::new(model, setup, &problem, &x0, &names, options);
    // (r, J) at the start, evaluated once: they judge what the design identifies, give the
    // residuals before, and are the first solve's first linearisation (a later solve, after
    // more parameters are held, starts at x0 again and evaluates it itself). Only the free
    // columns: the fixed ones are never read, and their pages of the zeroed buffer never touched.
    let mut r0 = vec![0.0; problem.residual_count()];
    let mut j0 = zeroed_matrix(problem.residual_count(), problem.parameter_count());
    problem
        .residuals_and_jacobian_of(&x0, &mut r0, &mut j0, &free)
        .map_err(|e| {
            unpredictable().unwrap_or_else(|| {
                FitError::Registration(format!(
                    "the model cannot be evaluated at the start: {}",
                    e.0
                ))
            })
        })?;
    let residuals_before = problem.unwhitened(&r0);
    // what the design can identify, judged at the start: a parameter whose effect is nil or a
    // combination of others there (e.g. a joint offset about the axis the target sits on) is
    // held before the solver can wander along it
    let (declared_identifiability, start_normal) = solving.identifiability_at_start(&j0, &free)?;
    let mut held = Vec::new();
    if !declared_identifiability.null_directions.is_empty() {
        // which parameters to hold is judged at the nominal machine (see
        // `Solving::jacobian_at_nominal_machine`), or at the start when that is the nominal one
        let nominal = solving.jacobian_at_nominal_machine(&j0, &free);
        solving.hold_dependent(nominal.as_ref().unwrap_or(&j0), &mut free, &mut held);
    }
    // the start's r and J go to the first solve, which works in them
    let start_normal = start_normal.filter(|_| held.is_empty());
    let solution = solving.two_stage(
        &free,
        Some(Evaluated {
            residuals: r0,
            jacobian: j0,
            normal_matrix: start_normal,
        }),
    )?;
    let (solution, identifiability) =
        solving.hold_until_identifiable(solution, &mut free, &mut held, n_free)?;
    let residuals_after = problem.unwhitened(&solution.residuals);
    let covariance = solution.covariance();
    let chi2: f64 = solution.residuals.iter().map(|r| r * r).sum();
    let dof = solution.degrees_of_freedom.max(1);
    let parameters = solving.estimates(&solution, &free);
    let threshold = match options.loss {
        Loss::Huber(c) | Loss::Cauchy(c) => Some(c),
        _ => None,
    };
    let outliers = match threshold {
        Some(c) => beyond_threshold(c, &solution, kept, &used),
        None => vec![],
    };
    Ok(Fit {
        parameters,
        x: solution.x.clone(),
        covariance,
        residuals_before,
        residuals_after,
        chi2_per_dof: chi2 / dof as f64,
        identifiability,
        downweighted: solution.downweighted,
        outliers,
        skipped,
        held,
        declared_identifiability,
        used,
        options_threshold: threshold,
        solution,
    })
}

/// The records with a non-finite value, named with the reason, and the indices of the others.
fn usable_records(records: &RecordSet) -> (Vec<RecordNote>, Vec<usize>) {
    let mut skipped = Vec::new();
    let mut used = Vec::new();
    for (i, r) in records.records.iter().enumerate() {
        let bad = if !r.measured.iter().all(|v| v.is_finite()) {
            Some("measured point is not finite (NaN or ∞)")
        } else if !r.q.iter().all(|v| v.is_finite()) {
            Some("commanded joints are not finite")
        } else if crate::residuals::whitening(&r.covariance).is_none() {
            Some("covariance is not finite and positive definite")
        } else {
            None
        };
        match bad {
            Some(reason) => skipped.push(RecordNote {
                index: i,
                point_id: r.point_id.clone(),
                time: r.time,
                reason: reason.into(),
            }),
            None => used.push(i),
        }
    }
    (skipped, used)
}

/// The setup's free parameters, the instrument poses held in the machine frame (the identity).
fn free_parameters(model: &ForwardModel, setup: &ParameterSetup, kept: &RecordSet) -> Vec<bool> {
    let mut free = setup.free.clone();
    if kept.frame == RecordFrame::Machine {
        for (_, pose) in model.pose_param_starts() {
            free[pose..pose + 6].iter_mut().for_each(|f| *f = false);
        }
    }
    free
}

/// The number of free parameters, or Err when `records` readings (3 each) and the priors on free
/// parameters are fewer, with the number of points to measure.
fn enough_readings(
    setup: &ParameterSetup,
    free: &[bool],
    records: usize,
) -> Result<usize, FitError> {
    let n_free = free.iter().filter(|f| **f).count();
    let n_priors = setup
        .priors
        .iter()
        .zip(free)
        .filter(|(p, f)| p.is_some() && **f)
        .count();
    if 3 * records + n_priors < n_free {
        return Err(FitError::TooFew {
            needed: n_free,
            available: 3 * records,
            points: n_free.div_ceil(3),
        });
    }
    Ok(n_free)
}

/// A record the model cannot predict (a missing signal, an unreachable joint vector), named with
/// its index and what would provide the signal; each record goes through its own instrument (a
/// probe hit does not read the tracker's air). None when every record can be predicted.
fn unpredictable_record(
    model: &ForwardModel,
    problem: &PointResiduals,
    kept: &RecordSet,
    used: &[usize],
) -> Option<FitError> {
    match problem.predictions_of_records(&model.params()) {
        Ok(_) => None,
        Err(EvaluationFailure::Model(e)) => Some(e.into()),
        Err(EvaluationFailure::Record { index, error }) => {
            let (hint, r) = (missing_signal_hint(&error), &kept.records[index]);
            Some(FitError::Record {
                index: used[index],
                point_id: r.point_id.clone(),
                time: r.time,
                source: error,
                hint,
            })
        }
    }
}

/// The records with a whitened component beyond the robust loss's threshold `c` at the solution.
fn beyond_threshold(
    c: f64,
    solution: &Solution,
    kept: &RecordSet,
    used: &[usize],
) -> Vec<RecordNote> {
    (0..kept.len())
        .filter_map(|i| {
            let z = &solution.residuals[3 * i..3 * i + 3];
            let worst = z.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            (worst > c).then(|| RecordNote {
                index: used[i],
                point_id: kept.records[i].point_id.clone(),
                time: kept.records[i].time,
                reason: format!("{worst:.1}σ from the model"),
            })
        })
        .collect()
}

/// What every solve of one fit shares: the problem and its start, the parameters' bounds (the
/// possible range, widened to include the start), priors, names and typical scales.
struct Solving<'p, 'm, 'a> {
    problem: &'p PointResiduals<'m, 'a>,
    x0: &'p [f64],
    options: &'p FitOptions,
    specs: Vec<metrocell_physics::ParamSpec>,
    names: &'p [String],
    labels: Vec<&'p str>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    priors: Vec<Prior>,
    /// The number of machine-term parameters (they come first in the stacked vector).
    machine_params: usize,
    /// Each parameter's typical change, for the nil-column test (units differ by 10⁹).
    scales: Vec<f64>,
}

impl<'p, 'm, 'a> Solving<'p, 'm, 'a> {
    fn new(
        model: &ForwardModel,
        setup: &ParameterSetup,
        problem: &'p PointResiduals<'m, 'a>,
        x0: &'p [f64],
        names: &'p [String],
        options: &'p FitOptions,
    ) -> Self {
        let specs: Vec<_> = model
            .machine_terms
            .param_specs()
            .into_iter()
            .chain(model.instrument_terms.param_specs())
            .collect();
        // bounds: the possible range (none for sign-free quantities), widened to include the
        // start so a start outside it is legal
        let lower: Vec<f64> = specs
            .iter()
            .zip(x0)
            .map(|(s, v)| s.possible.lo.min(*v))
            .collect();
        let upper: Vec<f64> = specs
            .iter()
            .zip(x0)
            .map(|(s, v)| s.possible.hi.max(*v))
            .collect();
        let priors: Vec<Prior> = setup
            .priors
            .iter()
            .enumerate()
            .filter_map(|(index, p)| {
                p.map(|p| Prior {
                    index,
                    value: p.value,
                    sigma: p.sigma,
                })
            })
            .collect();
        let scales = specs.iter().map(|s| s.typical_scale()).collect();
        Self {
            problem,
            x0,
            options,
            names,
            labels: names.iter().map(|s| s.as_str()).collect(),
            lower,
            upper,
            priors,
            machine_params: model.machine_terms.param_specs().len(),
            scales,
            specs,
        }
    }

    /// The solver's options for the free parameters `free` and the loss `loss`.
    fn solver_options(&self, free: &[bool], loss: Loss) -> Options {
        Options {
            loss,
            bounds: Some((self.lower.clone(), self.upper.clone())),
            fixed: free.iter().map(|f| !f).collect(),
            priors: self.priors.clone(),
            max_iterations: self.options.max_iterations,
            // stop when an accepted step lowers the cost by under 1e-12 of it, or moves the
            // scaled parameters by under 1e-12 of their norm: the cost of ~10⁴ readings is only
            // computed to ~1e-13 of itself, so tighter tolerances chase round-off (the last
            // iterations then report ρ of 10³–10⁸, a predicted reduction below the noise of the
            // actual one)
            ftol: 1e-12,
            xtol: 1e-12,
            gtol: 1e-12,
            null_space: NullSpace::Truncated {
                rcond: self.options.rcond,
            },
            // Marquardt's λ₀ = 1e-3 (relative to the unit-diagonal scaled normal matrix) damps
            // the weakly determined directions of a calibration (eigenvalues down to rcond² of
            // the largest) for several iterations while λ walks down; a calibration from its
            // start is nearly linear, and a step that overshoots is rejected and damped at the
            // price of one evaluation. On the XFYZ benchmark fit: 5 iterations → 4.
            initial_damping: 1e-6,
            ..Options::default()
        }
    }

    /// A solve from the start: a robust loss from a far start calls every residual an outlier
    /// and crawls, so the basin is reached with plain least squares first, then the robust loss
    /// judges the residuals.
    fn two_stage(&self, free: &[bool], at_start: Option<Evaluated>) -> Result<Solution, FitError> {
        let near = solve_from(
            self.problem,
            self.x0,
            at_start,
            &self.solver_options(free, Loss::Linear),
        )?;
        if self.options.loss == Loss::Linear {
            return Ok(near);
        }
        // the iterations and evaluations of both stages are the fit's
        let mut robust = solve(
            self.problem,
            &near.x,
            &self.solver_options(free, self.options.loss),
        )?;
        robust.iterations += near.iterations;
        robust.evaluations += near.evaluations;
        Ok(robust)
    }

    /// What the design identifies at the start (Jacobian `j0`), and the normal matrix of the
    /// free columns when the Gram route computed it (it is the first solve's too, when no
    /// parameter is held).
    fn identifiability_at_start(
        &self,
        j0: &DMatrix<f64>,
        free: &[bool],
    ) -> Result<(Identifiability, Option<DMatrix<f64>>), FitError> {
        let (priors, labels, rcond) = (&self.priors, &self.labels, self.options.rcond);
        let free_idx: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
        let free_labels: Vec<&str> = free_idx.iter().map(|&k| labels[k]).collect();
        Ok(if rcond >= GRAM_RCOND {
            let normal = normal_matrix(j0, &free_idx);
            let judged = if priors.is_empty() {
                Identifiability::from_normal_matrix(&normal, j0.nrows(), &free_labels, rcond)?
            } else {
                identifiability_with_priors(j0, priors, free, labels, rcond)?
            };
            (judged, Some(normal))
        } else if priors.is_empty() {
            (
                Identifiability::analyze(&j0.select_columns(&free_idx), &free_labels, Some(rcond))?,
                None,
            )
        } else {
            (
                identifiability_with_priors(j0, priors, free, labels, rcond)?,
                None,
            )
        })
    }

    /// What the design identifies at `solution`.
    fn judge(&self, solution: &Solution) -> Result<Identifiability, FitError> {
        Ok(if self.priors.is_empty() {
            solution.identifiability(&self.labels, Some(self.options.rcond))?
        } else {
            identifiability_with_priors(
                &solution.weighted_jacobian,
                &self.priors,
                &solution.free,
                &self.labels,
                self.options.rcond,
            )?
        })
    }

    /// The weighted Jacobian at the start with the machine's errors taken away: every
    /// machine-term parameter whose possible range holds 0 set to 0 (time constants, whose
    /// zero is no machine, keep their start), the free columns evaluated there. None when the
    /// start is that point already, or the model cannot be evaluated there.
    ///
    /// Why: a gauge freedom — a turn of the tracker against a straightness's slope and a
    /// squareness, a shift of it against an offset — is an exact dependence of the columns only
    /// where the machine has no errors: the tracker turns the *displaced* point, the machine
    /// terms act on the nominal one. At a start with errors in it (a handbook α of a scale's
    /// expansion, a model fitted before) the dependence is broken by the errors' relative size
    /// (~1e-5…1e-4), above the column test's threshold, so the gauge parameter was kept and the
    /// fit stated σ of millimetres for a slope and the whole map (found on an independent
    /// verification export: positioning[x].c1 ± 167 µm, condition number 8.7e5, with
    /// `alpha: 11.5e-6` as the start; 0.56 µm with the same data started at α = 0). A column the
    /// nominal machine leaves nil (a lag's time constant with its coefficient zeroed) is judged
    /// as it is at the start.
    fn jacobian_at_nominal_machine(
        &self,
        j0: &DMatrix<f64>,
        free: &[bool],
    ) -> Option<DMatrix<f64>> {
        let mut x = self.x0.to_vec();
        let mut moved = false;
        for k in 0..self.machine_params {
            let s = &self.specs[k];
            if x[k] != 0.0 && s.possible.lo <= 0.0 && s.possible.hi >= 0.0 && s.unit != "s" {
                x[k] = 0.0;
                moved = true;
            }
        }
        if !moved {
            return None;
        }
        let mut r = vec![0.0; self.problem.residual_count()];
        let mut j = zeroed_matrix(
            self.problem.residual_count(),
            self.problem.parameter_count(),
        );
        self.problem
            .residuals_and_jacobian_of(&x, &mut r, &mut j, free)
            .ok()?;
        for k in (0..free.len()).filter(|&k| free[k]) {
            let start = j0.column(k).norm();
            if !(j.column(k).norm() > 1e-9 * start) {
                j.set_column(k, &j0.column(k));
            }
        }
        Some(j)
    }

    /// Hold each free parameter the columns of `jw` show dependent on others (a machine-term
    /// parameter rather than the pose), naming the combination.
    fn hold_dependent(&self, jw: &DMatrix<f64>, free: &mut [bool], held: &mut Vec<HeldParameter>) {
        for (k, sentence) in dependent_parameters(
            &with_prior_rows(jw, &self.priors),
            free,
            self.machine_params,
            self.names,
            &self.scales,
        ) {
            free[k] = false;
            held.push(HeldParameter {
                index: k,
                name: self.names[k].clone(),
                combination: sentence,
            });
        }
    }

    /// At the solution: hold what became inseparable there too (solving from the start again, so
    /// the held ones keep their start values exactly) until the rest is identifiable; the last
    /// solution and what it identifies.
    fn hold_until_identifiable(
        &self,
        mut solution: Solution,
        free: &mut [bool],
        held: &mut Vec<HeldParameter>,
        n_free: usize,
    ) -> Result<(Solution, Identifiability), FitError> {
        let mut identifiability = self.judge(&solution)?;
        while !identifiability.null_directions.is_empty() && held.len() < n_free {
            let before = held.len();
            self.hold_dependent(&solution.weighted_jacobian, free, held);
            if held.len() == before {
                // numerically weak directions the column test does not call dependent: hold the
                // weakest direction's leading parameter
                let d = &identifiability.null_directions[0];
                let free_idx: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
                let j = (0..d.scaled.len()).fold(0, |b, j| {
                    if d.scaled[j].abs() > d.scaled[b].abs() {
                        j
                    } else {
                        b
                    }
                });
                let k = free_idx[j];
                free[k] = false;
                held.push(HeldParameter {
                    index: k,
                    name: self.names[k].clone(),
                    combination: identifiability.describe()[0].clone(),
                });
            }
            solution = self.two_stage(free, None)?;
            identifiability = self.judge(&solution)?;
        }
        Ok((solution, identifiability))
    }

    /// Every parameter's estimate at `solution`: σ and the bound reached for the free ones.
    fn estimates(&self, solution: &Solution, free: &[bool]) -> Vec<ParameterEstimate> {
        let sigmas = solution.standard_uncertainties();
        self.specs
            .iter()
            .enumerate()
            .map(|(k, s)| ParameterEstimate {
                name: self.names[k].clone(),
                value: solution.x[k],
                sigma: if free[k] {
                    sigmas.as_ref().map(|u| u[k])
                } else {
                    None
                },
                unit: s.unit,
                free: free[k],
                range: (s.possible.lo, s.possible.hi),
                usual: (s.usual.lo, s.usual.hi),
                at_bound: if free[k] {
                    bound_reached(
                        solution.x[k],
                        self.lower[k],
                        self.upper[k],
                        s.typical_scale(),
                    )
                } else {
                    None
                },
            })
            .collect()
    }
}

/// √W·J with one row per prior (1/σ in its parameter's column): a prior is information too —
/// a levelled instrument's compensator is what separates its placements' tilts from the base's.
/// `j` itself (borrowed, not copied) without priors.
fn with_prior_rows<'j>(
    j: &'j DMatrix<f64>,
    priors: &[Prior],
) -> std::borrow::Cow<'j, DMatrix<f64>> {
    if priors.is_empty() {
        return std::borrow::Cow::Borrowed(j);
    }
    let mut out = j.clone().resize_vertically(j.nrows() + priors.len(), 0.0);
    for (i, p) in priors.iter().enumerate() {
        out[(j.nrows() + i, p.index)] = 1.0 / p.sigma;
    }
    std::borrow::Cow::Owned(out)
}

/// What the measurements and the priors identify together, over the `free` parameters.
fn identifiability_with_priors(
    jw: &DMatrix<f64>,
    priors: &[Prior],
    free: &[bool],
    labels: &[&str],
    rcond: f64,
) -> Result<Identifiability, SolverError> {
    let idx: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
    let names: Vec<&str> = idx.iter().map(|&k| labels[k]).collect();
    let all = with_prior_rows(jw, priors);
    if rcond >= GRAM_RCOND {
        Identifiability::from_normal_matrix(&normal_matrix(&all, &idx), all.nrows(), &names, rcond)
    } else {
        Identifiability::analyze(&all.select_columns(&idx), &names, Some(rcond))
    }
}

/// Relative size (of a unit column) below which a column is taken as a combination of the
/// columns kept before it. Structural dependence leaves ~1e-12 (more after round-off in a
/// badly scaled model); 10× the fit's default `rcond`, so that what this test keeps is not
/// called unidentifiable by the SVD at the solution — the margin keeps the held set the same
/// whatever the noise.
const DEPENDENT: f64 = 1e-5;

/// The free parameters whose (weighted, unit-scaled) Jacobian column is a combination of the
/// columns kept before it, in a fixed priority order — instrument parameters first (the
/// instrument pose is a nuisance that absorbs what it can), then machine coefficients of order
/// ≥ 1, then the constants `c0` (a constant offset is the conventional one to hold) — with a
/// sentence naming the parameters it cannot be told from. Deterministic for a design: the
/// noise moves the columns far less than the threshold.
fn dependent_parameters(
    jw: &DMatrix<f64>,
    free: &[bool],
    machine_params: usize,
    names: &[String],
    scales: &[f64],
) -> Vec<(usize, String)> {
    let mut order: Vec<usize> = (machine_params..free.len()).filter(|&k| free[k]).collect();
    // squareness before the series: ISO 230-1 refers straightness to its reference line, so a
    // linear straightness term is what gives way to the squareness it aliases
    order.extend((0..machine_params).filter(|&k| free[k] && names[k].starts_with("squareness")));
    order.extend(
        (0..machine_params).filter(|&k| {
            free[k] && !names[k].starts_with("squareness") && !names[k].ends_with(".c0")
        }),
    );
    order.extend((0..machine_params).filter(|&k| free[k] && names[k].ends_with(".c0")));
    inseparable_at_scales(jw, &order, names, Some(scales))
}

/// The columns of `jw` (parameters `names`) among `order` that are combinations of columns
/// earlier in `order` (those are kept), each with a sentence naming what it cannot be told
/// from and the combination that leaves every residual unchanged. Columns are compared scaled
/// to unit norm; a nil column (below 1e-9 of the largest) is "not identifiable".
pub fn inseparable(jw: &DMatrix<f64>, order: &[usize], names: &[String]) -> Vec<(usize, String)> {
    inseparable_at_scales(jw, order, names, None)
}

/// [`inseparable`] with each parameter's typical size (`scales[k]`, its unit's worth of a
/// usual change: a time constant's hours, a pretravel's µm): a column is nil when its effect
/// over a typical change is below 1e-9 of the largest such effect, whatever the units — per
/// unit parameter a time constant in seconds moves a reading 10⁻⁹ as much as a pretravel in
/// metres and would be called nil beside it.
pub fn inseparable_at_scales(
    jw: &DMatrix<f64>,
    order: &[usize],
    names: &[String],
    scales: Option<&[f64]>,
) -> Vec<(usize, String)> {
    let scale = |k: usize| scales.map_or(1.0, |s| s[k]);
    let largest = order
        .iter()
        .map(|&k| jw.column(k).norm() * scale(k))
        .fold(0.0f64, f64::max);
    // the Gram matrix of the columns in `order` (position in `order` → row/column), for the
    // combinations below: their least squares on the kept columns is a small solve on it, where
    // an SVD of the m × kept columns per dependent column took seconds (29 dependent columns of
    // a 30 000-row XFYZ Jacobian: 4.8 s of a 5 s fit)
    let selected = jw.select_columns(order);
    let gram = selected.tr_mul(&selected);
    let position = |k: usize| {
        order
            .iter()
            .position(|&o| o == k)
            .expect("a column of `order`")
    };
    // orthonormal basis of the kept columns (modified Gram–Schmidt), and each kept column's norm
    let mut basis: Vec<nalgebra::DVector<f64>> = Vec::new();
    let mut kept: Vec<(usize, f64)> = Vec::new();
    let mut out = Vec::new();
    for &k in order {
        let col = jw.column(k).into_owned();
        let norm = col.norm();
        if !(norm * scale(k) > 1e-9 * largest) {
            out.push((
                k,
                format!(
                    "{} is not identifiable: no measurement depends on it; held at its start value",
                    names[k]
                ),
            ));
            continue;
        }
        let mut r = col / norm;
        // Gram–Schmidt twice ("twice is enough"): one pass loses orthogonality in proportion to
        // the conditioning, which would let a dependent column through
        for _ in 0..2 {
            for b in &basis {
                let c = b.dot(&r);
                r -= b * c;
            }
        }
        let rest = r.norm();
        if rest > DEPENDENT {
            basis.push(r / rest);
            kept.push((k, norm));
            continue;
        }
        // express the column by the kept ones: least squares on the unit columns, by its normal
        // equations (the kept columns are independent to DEPENDENT, so squaring their
        // conditioning still leaves the three digits the sentence prints)
        let at = kept
            .iter()
            .map(|&(j, nj)| (position(j), nj))
            .collect::<Vec<_>>();
        let pk = position(k);
        let a = DMatrix::from_fn(at.len(), at.len(), |i, j| {
            gram[(at[i].0, at[j].0)] / (at[i].1 * at[j].1)
        });
        let b = nalgebra::DVector::from_fn(at.len(), |i, _| gram[(at[i].0, pk)] / (at[i].1 * norm));
        let coef = a
            .svd(true, true)
            .solve(&b, 1e-12)
            .unwrap_or_else(|_| nalgebra::DVector::zeros(kept.len()));
        let max = coef.iter().fold(0.0f64, |x, c| x.max(c.abs()));
        let mut parts = Vec::new();
        for (j, c) in coef.iter().enumerate() {
            if c.abs() > 1e-3 * max {
                // δk = 1 (parameter units) is matched by δj = −c·norm_k/norm_j
                let d = -c * norm / kept[j].1;
                parts.push((names[kept[j].0].clone(), d));
            }
        }
        let with: Vec<String> = parts.iter().map(|(n, _)| n.clone()).collect();
        let how: Vec<String> = parts
            .iter()
            .map(|(n, d)| {
                format!(
                    "{} {}·{n}",
                    if *d < 0.0 { "−" } else { "+" },
                    significant(d.abs())
                )
            })
            .collect();
        out.push((k, format!("{} is not separable from {}: moving it by δ and the others by {} δ leaves every residual unchanged; held at its start value", names[k], with.join(", "), how.join(" "))));
    }
    out
}

/// Three significant digits.
fn significant(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..4).contains(&e) {
        format!("{:.*}", (2 - e).max(0) as usize, x)
    } else {
        format!("{x:.2e}")
    }
}
