//! Batch identification: the declared model's free parameters fitted to measured points.
//!
//! What it does, in order:
//! 1. Frame: records in the machine frame fix the instrument pose at the identity; records in an
//!    instrument frame start the pose from a weighted Kabsch registration of the measured points
//!    to the model's tool points (crates/tracker `registration`), so an export in any tracker
//!    placement converges, and leave it free unless the model file fixes it.
//! 2. Levenberg–Marquardt (crates/solver) on [`PointResiduals`], bounded by each parameter's
//!    documented range, with the model file's priors, a robust loss if asked (outliers that
//!    slipped through are down-weighted and counted, not silently kept), and truncated-SVD steps
//!    so that combinations the data cannot separate stay at their start (minimum-norm solution
//!    on the identifiable subspace).
//! 3. Honest uncertainty: covariance (JᵀWJ)⁻¹ scaled by the a-posteriori variance factor σ̂₀²,
//!    standard uncertainties, correlations, and the identifiability analysis (rank, condition
//!    number, each unidentifiable combination in words).

use metrocell_model::{ForwardModel, ParameterSetup};
use metrocell_physics::{PhysicsError, TermId};
use metrocell_solver::{solve, Identifiability, Loss, NullSpace, Options, Prior, Solution, SolverError};
use metrocell_laser_tracker::registration::{register, Correspondence};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::records::{RecordFrame, RecordSet};
use crate::residuals::PointResiduals;

/// Settings of a batch fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Loss on the whitened residuals; Huber at 4σ keeps honest data quadratic (6e-5 of Gaussian components exceed it) and limits what
    /// an outlier can pull.
    pub loss: Loss,
    pub max_iterations: usize,
    /// Relative singular value below which a direction counts as unidentifiable.
    pub rcond: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { loss: Loss::Huber(4.0), max_iterations: 100, rcond: 1e-9 }
    }
}

/// Why a fit could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("no usable measurements (every record was rejected or the recording has none)")]
    NoRecords,
    #[error("record {index} (point `{point_id}`): its covariance is not finite and positive definite")]
    BadCovariance { index: usize, point_id: String },
    #[error("{0}")]
    Model(#[from] PhysicsError),
    #[error("the instrument pose could not be registered from the points: {0}")]
    Registration(String),
    #[error("{0}")]
    Solver(#[from] SolverError),
    #[error("{needed} parameters are free but only {available} residuals: measure at least {points} points")]
    TooFew { needed: usize, available: usize, points: usize },
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
    /// Documented plausible range.
    pub range: (f64, f64),
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
    pub solution: Solution,
}

impl Fit {
    pub fn parameter(&self, name: &str) -> Option<&ParameterEstimate> {
        self.parameters.iter().find(|p| p.name == name)
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
pub fn start_vector(model: &ForwardModel, setup: &ParameterSetup, records: &RecordSet) -> Result<Vec<f64>, FitError> {
    let mut x = model.params();
    let Some(pose) = model.instrument_param_start(TermId::TrackerPose) else { return Ok(x) };
    match &records.frame {
        RecordFrame::Machine => x[pose..pose + 6].iter_mut().for_each(|v| *v = 0.0),
        RecordFrame::Instrument(_) if setup.free[pose..pose + 6].iter().any(|f| *f) => {
            let kin = model.kinematic_truth(&x)?;
            let mut pairs = Vec::with_capacity(records.len());
            for r in &records.records {
                let mut s = r.signals.clone();
                let tool = model.tool_state(&x, &kin, &r.q, &mut s, None)?;
                pairs.push(Correspondence { tracker: r.measured, tracker_covariance: r.covariance, machine: tool.truth.translation.vector, machine_covariance: Matrix3::identity() * 1e-12 });
            }
            let reg = register(&pairs).map_err(|e| FitError::Registration(e.to_string()))?;
            let p = metrocell_model::InstrumentPose::from_rotation(reg.translation, reg.rotation.matrix());
            x[pose..pose + 6].copy_from_slice(&p.term_params());
        }
        RecordFrame::Instrument(_) => {}
    }
    Ok(x)
}

/// Fit the free parameters of `setup` to `records` from `start` (None: [`start_vector`]).
pub fn fit(model: &ForwardModel, setup: &ParameterSetup, records: &RecordSet, start: Option<Vec<f64>>, options: &FitOptions) -> Result<Fit, FitError> {
    if records.is_empty() {
        return Err(FitError::NoRecords);
    }
    let mut free = setup.free.clone();
    if let (RecordFrame::Machine, Some(pose)) = (&records.frame, model.instrument_param_start(TermId::TrackerPose)) {
        free[pose..pose + 6].iter_mut().for_each(|f| *f = false);
    }
    let n_free = free.iter().filter(|f| **f).count();
    let n_priors = setup.priors.iter().zip(&free).filter(|(p, f)| p.is_some() && **f).count();
    if 3 * records.len() + n_priors < n_free {
        return Err(FitError::TooFew { needed: n_free, available: 3 * records.len(), points: n_free.div_ceil(3) });
    }
    let x0 = match start {
        Some(x) => x,
        None => start_vector(model, setup, records)?,
    };
    let problem = PointResiduals::new(model, &records.records).map_err(|b| FitError::BadCovariance { index: b.index, point_id: b.point_id })?;
    let specs: Vec<_> = model.machine_terms.param_specs().into_iter().chain(model.instrument_terms.param_specs()).collect();
    // bounds: the documented range, widened to include the start so a start outside it is legal
    let lower: Vec<f64> = specs.iter().zip(&x0).map(|(s, v)| s.min.min(*v)).collect();
    let upper: Vec<f64> = specs.iter().zip(&x0).map(|(s, v)| s.max.max(*v)).collect();
    let priors: Vec<Prior> = setup.priors.iter().enumerate().filter_map(|(index, p)| p.map(|p| Prior { index, value: p.value, sigma: p.sigma })).collect();
    let solver_options = Options {
        loss: options.loss,
        bounds: Some((lower, upper)),
        fixed: free.iter().map(|f| !f).collect(),
        priors,
        max_iterations: options.max_iterations,
        ftol: 1e-14,
        xtol: 1e-14,
        gtol: 1e-12,
        null_space: NullSpace::Truncated { rcond: options.rcond },
        ..Options::default()
    };
    let residuals_before = problem.raw_residuals(&x0)?;
    let solution = solve(&problem, &x0, &solver_options)?;
    let residuals_after = problem.raw_residuals(&solution.x)?;
    let names = model.param_names();
    let labels: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let identifiability = solution.identifiability(&labels, Some(options.rcond))?;
    let covariance = solution.covariance();
    let sigmas = solution.standard_uncertainties();
    let chi2: f64 = solution.residuals.iter().map(|r| r * r).sum();
    let dof = solution.degrees_of_freedom.max(1);
    let parameters = specs
        .iter()
        .enumerate()
        .map(|(k, s)| ParameterEstimate {
            name: names[k].clone(),
            value: solution.x[k],
            sigma: if free[k] { sigmas.as_ref().map(|u| u[k]) } else { None },
            unit: s.unit,
            free: free[k],
            range: (s.min, s.max),
        })
        .collect();
    Ok(Fit { parameters, x: solution.x.clone(), covariance, residuals_before, residuals_after, chi2_per_dof: chi2 / dof as f64, identifiability, downweighted: solution.downweighted, solution })
}
