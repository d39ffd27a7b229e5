//! The uncertainty of a verification as it was measured: seed 001 P3's Monte Carlo run on the
//! user's own readings. P3 takes "approximation functions obtained in previous verification"
//! as the generation truth; here that is the fit of this verification. Each trial redraws
//! every reading's noise from its stated covariance around the fit's prediction, fits again as
//! the verification was fitted (tracker pose registered and identified with the errors), and
//! evaluates the error map: the spread of the maps is the map's uncertainty, and the
//! difference between the generating and the refitted map is the residual volumetric error a
//! compensation from such a verification leaves.
//!
//! What it cannot see: physics the model lacks (a misfit shows as χ²/dof ≫ 1, which the report
//! states) and noise the readings' covariance understates.

use metrocell_estimation::map_gauge::MapGauge;
use metrocell_estimation::volumetric_monte_carlo::{volumetric_monte_carlo, VolumetricMonteCarlo};
use metrocell_estimation::{Fit, FitError, FitOptions, RecordSet};
use metrocell_model::{ForwardModel, ParameterSetup};
use metrocell_physics::Signals;
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// A square root L of a reading's covariance (L·Lᵀ = C): Cholesky, or the diagonal's roots
/// when C is not positive definite.
fn square_root(c: &Matrix3<f64>) -> Matrix3<f64> {
    match c.cholesky() {
        Some(ch) => ch.l(),
        None => Matrix3::from_diagonal(&c.diagonal().map(|v| v.max(0.0).sqrt())),
    }
}

/// The readings the fit used, moved to its prediction, with noise drawn from each one's
/// covariance (seeded).
pub fn redrawn(records: &RecordSet, f: &Fit, seed: u64) -> RecordSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = RecordSet {
        frame: records.frame.clone(),
        records: Vec::with_capacity(f.used.len()),
        check: vec![],
        rejected: vec![],
        sources: records.sources.clone(),
    };
    for (&i, r) in f.used.iter().zip(&f.residuals_after) {
        let mut rec = records.records[i].clone();
        let n = Vector3::from_fn(|_, _| StandardNormal.sample(&mut rng));
        rec.measured = rec.measured - r + square_root(&rec.covariance) * n;
        out.records.push(rec);
    }
    out
}

/// `trials` verifications redrawn from `f` (the fit of `records` with `setup`), each fitted
/// with `options`; the error map at `points` under `conditions`, in `gauge`. `progress(k)` is
/// called before trial k.
#[allow(clippy::too_many_arguments)]
pub fn resampled_monte_carlo(
    model: &ForwardModel,
    setup: &ParameterSetup,
    records: &RecordSet,
    f: &Fit,
    points: &[Vec<f64>],
    conditions: &Signals,
    gauge: MapGauge,
    trials: usize,
    seed: u64,
    options: &FitOptions,
    mut progress: impl FnMut(usize),
) -> Result<VolumetricMonteCarlo, FitError> {
    volumetric_monte_carlo(
        model,
        setup,
        &f.x,
        points,
        conditions,
        gauge,
        trials,
        |k| {
            progress(k);
            (redrawn(records, f, seed.wrapping_add(k as u64)), None)
        },
        options,
    )
}
