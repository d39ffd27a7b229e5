//! Monte Carlo of a volumetric verification (seed 001, P3/P4): N simulated verifications —
//! each with its own instrument noise and, if the caller wants, its own tracker placement —
//! fitted like a real one; the spread of the fitted error map is its uncertainty, and the
//! difference between the fitted and the true error at verification points is the residual
//! volumetric error after compensation (the thesis's "12.34 ± 7.06 µm").
//!
//! Error map: e(q) = true − nominal tool point of the machine terms at the commanded axis
//! position q (the model's tool state), in the workpiece frame, at the stated conditions.

use metrocell_model::{ForwardModel, ParameterSetup};
use metrocell_physics::Signals;
use nalgebra::Vector3;

use crate::fit::{fit, FitError, FitOptions};
use crate::map_gauge::MapGauge;
use crate::records::RecordSet;

/// What N simulated verifications say.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumetricMonteCarlo {
    /// Verification points (commanded joint vectors).
    pub points: Vec<Vec<f64>>,
    /// The true error at each point (m).
    pub true_errors: Vec<Vector3<f64>>,
    /// Mean and standard deviation over the trials of the fitted error at each point (m): the
    /// error map and its uncertainty.
    pub mean_fitted: Vec<Vector3<f64>>,
    pub sd_fitted: Vec<Vector3<f64>>,
    /// |true error| at each point: the volumetric error before compensation (m).
    pub initial_moduli: Vec<f64>,
    /// |true − fitted error| at every point of every successful trial: the residual volumetric
    /// error after compensation (m).
    pub residual_moduli: Vec<f64>,
    /// The linearised standard uncertainty of the fitted error at each point from the first
    /// trial's covariance (m), to compare with `sd_fitted`.
    pub linearised_sd: Vec<Vector3<f64>>,
    pub trials: usize,
    /// Trials whose fit failed (counted, not hidden).
    pub failed: usize,
}

/// Mean and sample standard deviation.
pub fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    (
        m,
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt(),
    )
}

/// The conditions with the axes at `q`, at rest, approached in +.
fn signals_at(model: &ForwardModel, q: &[f64], conditions: &Signals) -> Signals {
    let mut s = conditions.clone();
    if q.len() >= 3 {
        model.set_motion(&mut s, q, &[0.0; 3], &[1.0; 3]);
    }
    s
}

/// The error map of `model` at parameters `p` at the joint vectors `points`.
pub fn error_map(
    model: &ForwardModel,
    p: &[f64],
    points: &[Vec<f64>],
    conditions: &Signals,
) -> Result<Vec<Vector3<f64>>, FitError> {
    let kin = model.kinematic_truth(p)?;
    points
        .iter()
        .map(|q| {
            let mut s = signals_at(model, q, conditions);
            Ok(model.tool_state(p, &kin, q, &mut s, None)?.d)
        })
        .collect()
}

/// Run `trials` verifications: `trial(k)` simulates trial k's measurements (noise, placement)
/// and gives the fit's start vector (None: the model's start; e.g. the placed tracker's pose
/// when the placement is known, as in seed 001's P3); each is fitted with `setup` and
/// `options`; the fitted error map at `points` is compared with the truth's, both stated in
/// `gauge` (see [`crate::map_gauge`]: a freely placed instrument fixes a map only up to a rigid
/// motion).
#[allow(clippy::too_many_arguments)]
pub fn volumetric_monte_carlo(
    model: &ForwardModel,
    setup: &ParameterSetup,
    truth: &[f64],
    points: &[Vec<f64>],
    conditions: &Signals,
    gauge: MapGauge,
    trials: usize,
    mut trial: impl FnMut(usize) -> (RecordSet, Option<Vec<f64>>),
    options: &FitOptions,
) -> Result<VolumetricMonteCarlo, FitError> {
    let mut true_errors = error_map(model, truth, points, conditions)?;
    gauge.apply(points, &mut true_errors);
    let n = points.len();
    let mut sum = vec![Vector3::zeros(); n];
    let mut sum_sq = vec![Vector3::zeros(); n];
    let mut residual_moduli = Vec::with_capacity(trials * n);
    let mut linearised_sd = vec![];
    let mut ok = 0;
    let mut failed = 0;
    for k in 0..trials {
        let (records, start) = trial(k);
        let Ok(f) = fit(model, setup, &records, start, options) else {
            failed += 1;
            continue;
        };
        let mut fitted = error_map(model, &f.x, points, conditions)?;
        gauge.apply(points, &mut fitted);
        if linearised_sd.is_empty() {
            linearised_sd = error_map_sd(model, &f.x, f.covariance.as_ref(), points, conditions)?;
        }
        for i in 0..n {
            sum[i] += fitted[i];
            sum_sq[i] += fitted[i].component_mul(&fitted[i]);
            residual_moduli.push((true_errors[i] - fitted[i]).norm());
        }
        ok += 1;
    }
    let m = ok.max(1) as f64;
    let mean_fitted: Vec<Vector3<f64>> = sum.iter().map(|s| s / m).collect();
    let sd_fitted = sum_sq
        .iter()
        .zip(&mean_fitted)
        .map(|(sq, mu)| {
            ((sq / m - mu.component_mul(mu)) * m / (m - 1.0).max(1.0)).map(|v| v.max(0.0).sqrt())
        })
        .collect();
    Ok(VolumetricMonteCarlo {
        points: points.to_vec(),
        initial_moduli: true_errors.iter().map(|e| e.norm()).collect(),
        true_errors,
        mean_fitted,
        sd_fitted,
        residual_moduli,
        linearised_sd,
        trials,
        failed,
    })
}

/// √diag(J·C·Jᵀ) of the error map at `points` (zero without a covariance): the linearised
/// standard uncertainty of each component of the error a fit with covariance C gives there.
pub fn error_map_sd(
    model: &ForwardModel,
    p: &[f64],
    covariance: Option<&nalgebra::DMatrix<f64>>,
    points: &[Vec<f64>],
    conditions: &Signals,
) -> Result<Vec<Vector3<f64>>, FitError> {
    let Some(c) = covariance else {
        return Ok(vec![Vector3::zeros(); points.len()]);
    };
    let kin = model.kinematic_truth(p)?;
    let mut j = nalgebra::DMatrix::zeros(3, model.param_count());
    points
        .iter()
        .map(|q| {
            let mut s = signals_at(model, q, conditions);
            model.tool_point_jacobian(p, &kin, q, &mut s, &mut j)?;
            let jc = &j * c;
            Ok(Vector3::from_fn(|i, _| {
                jc.row(i).dot(&j.row(i)).max(0.0).sqrt()
            }))
        })
        .collect()
}
