//! The ranges the online filter keeps a parameter in, and how far its uncertainty may open.
//!
//! Two readings of a parameter's catalog spec (crates/physics `ParamSpec`), each through one
//! function so the catalog's split into a *usual* and a *possible* range changes one line here:
//! * [`start_range`]: the range whose half-width is the start σ of a parameter without a prior
//!   (the one a user's machine usually lies in);
//! * [`possible_range`]: outside it a value is impossible; the filter's state is held inside it,
//!   so every published model is one a user can apply.
//!
//! The covariance never opens beyond what the filter knew before any data (its prior, itself
//! no wider than half the possible range): [`fade_toward_prior`] re-opens it on an alarm only
//! along the directions the data inform.

use metrocell_physics::ParamSpec;
use nalgebra::DMatrix;

/// The range (min, max) outside which the parameter is impossible (±∞ where it has no bound).
pub fn possible_range(spec: &ParamSpec) -> (f64, f64) {
    (spec.possible.lo, spec.possible.hi)
}

/// The range whose half-width is a parameter's start σ when the model gives no prior: the usual
/// one (where a user's machine usually lies).
pub fn start_range(spec: &ParamSpec) -> (f64, f64) {
    (spec.usual.lo, spec.usual.hi)
}

/// Half the width of the possible range: no σ of the filter exceeds it.
pub fn possible_half_width(spec: &ParamSpec) -> f64 {
    let (lo, hi) = possible_range(spec);
    0.5 * (hi - lo)
}

/// Forget the data by `factor` and keep the prior: in information form
/// P⁻¹ ← P₀⁻¹ + (P⁻¹ − P₀⁻¹)/factor, with P₀ = diag(σ₀²).
///
/// Along a direction the data inform well the variance grows by ≈ `factor` (the filter
/// re-converges to a changed machine instead of averaging over the change); along one the data
/// do not inform (the variance still at the prior) nothing changes; no variance grows beyond the
/// prior's. Computed in prior-whitened coordinates P̃ = D⁻¹PD⁻¹ (D = diag σ₀) without inverting
/// P: P̃ ← factor·((factor − 1)·P̃ + I)⁻¹·P̃, whose matrix to factor has every eigenvalue ≥ 1.
/// A direction already wider than the prior (a random walk ran long) is brought back to it.
/// A parameter with σ₀ = 0 keeps its row and column.
pub fn fade_toward_prior(p: &DMatrix<f64>, sigma0: &[f64], factor: f64) -> DMatrix<f64> {
    let k = p.nrows();
    if factor <= 1.0 || k == 0 {
        return p.clone();
    }
    let inv = |s: f64| if s > 0.0 { 1.0 / s } else { 0.0 };
    let white = DMatrix::from_fn(k, k, |i, j| p[(i, j)] * inv(sigma0[i]) * inv(sigma0[j]));
    let a = &white * (factor - 1.0) + DMatrix::identity(k, k);
    let Some(chol) = a.cholesky() else {
        // P not positive semi-definite (rounding): leave it rather than make it worse
        return p.clone();
    };
    let faded = chol.solve(&white) * factor;
    DMatrix::from_fn(k, k, |i, j| {
        if sigma0[i] > 0.0 && sigma0[j] > 0.0 {
            0.5 * (faded[(i, j)] + faded[(j, i)]) * sigma0[i] * sigma0[j]
        } else {
            p[(i, j)]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fading_opens_informed_directions_and_keeps_the_prior_elsewhere() {
        // parameter 0 well measured (σ 1 % of its prior), parameter 1 untouched by data,
        // parameter 2 at half its prior σ
        let sigma0 = [10.0, 5.0, 2.0];
        let p = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![
            0.1f64.powi(2),
            25.0,
            1.0,
        ]));
        let q = fade_toward_prior(&p, &sigma0, 100.0);
        // information form by hand: 1/P' = 1/P0 + (1/P − 1/P0)/100
        for i in 0..3 {
            let (p0, pi) = (sigma0[i] * sigma0[i], p[(i, i)]);
            let expected = 1.0 / (1.0 / p0 + (1.0 / pi - 1.0 / p0) / 100.0);
            assert!(
                (q[(i, i)] - expected).abs() <= 1e-12 * expected,
                "{i}: {} vs {expected}",
                q[(i, i)]
            );
            assert!(q[(i, i)] <= p0 * (1.0 + 1e-12), "never beyond the prior");
        }
        assert!(
            (q[(0, 0)] / p[(0, 0)] - 100.0).abs() < 1.0,
            "the well-measured direction opens ≈ 100×"
        );
        assert_eq!(
            q[(1, 1)],
            25.0,
            "the unmeasured direction stays at its prior"
        );
        // however often it is repeated
        let mut r = p.clone();
        for _ in 0..50 {
            r = fade_toward_prior(&r, &sigma0, 100.0);
        }
        for i in 0..3 {
            assert!(
                r[(i, i)] <= sigma0[i] * sigma0[i] * (1.0 + 1e-9),
                "{i}: {} after 50 alarms",
                r[(i, i)]
            );
        }
    }

    #[test]
    fn a_correlated_pair_opens_only_along_what_the_data_measured() {
        // two parameters with prior σ 1 whose sum is measured to 0.01 and difference not at all
        let sigma0 = [1.0, 1.0];
        let s = 0.01f64;
        // P = ½[[1+s², s²−1],[s²−1, 1+s²]]: sum variance 2s², difference variance 2
        let p = DMatrix::from_row_slice(
            2,
            2,
            &[
                0.5 * (1.0 + s * s),
                0.5 * (s * s - 1.0),
                0.5 * (s * s - 1.0),
                0.5 * (1.0 + s * s),
            ],
        );
        let q = fade_toward_prior(&p, &sigma0, 100.0);
        let along = |m: &DMatrix<f64>, v: [f64; 2]| {
            v[0] * (m[(0, 0)] * v[0] + m[(0, 1)] * v[1])
                + v[1] * (m[(1, 0)] * v[0] + m[(1, 1)] * v[1])
        };
        let (sum, diff) = (
            [0.5f64.sqrt(), 0.5f64.sqrt()],
            [0.5f64.sqrt(), -(0.5f64.sqrt())],
        );
        assert!(
            (along(&q, diff) - along(&p, diff)).abs() < 1e-12,
            "the unmeasured difference keeps its variance"
        );
        assert!(
            (along(&q, sum) / along(&p, sum) - 100.0).abs() < 1.0,
            "the measured sum opens"
        );
    }
}
