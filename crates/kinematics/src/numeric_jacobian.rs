//! Central finite differences, used to check the analytic Jacobians and for models without one.

use nalgebra::{DMatrix, DVector};

/// Central-difference Jacobian of `f` at `x`, with per-coordinate step `h_i = step · max(1, |x_i|)`.
/// Error is O(h²); `step ≈ 1e-6` balances truncation and rounding for smooth functions of O(1) inputs.
/// Returns `None` when `f` fails at a stepped point.
pub fn central_difference<F>(f: F, x: &DVector<f64>, step: f64) -> Option<DMatrix<f64>>
where
    F: Fn(&DVector<f64>) -> Option<DVector<f64>>,
{
    let f0 = f(x)?;
    let mut j = DMatrix::zeros(f0.len(), x.len());
    for i in 0..x.len() {
        let h = step * x[i].abs().max(1.0);
        let mut xp = x.clone();
        xp[i] += h;
        let mut xm = x.clone();
        xm[i] -= h;
        let d = (f(&xp)? - f(&xm)?) / (2.0 * h);
        j.set_column(i, &d);
    }
    Some(j)
}

/// Largest element-wise discrepancy between two Jacobians, relative to the largest magnitude in `reference`.
pub fn max_relative_difference(a: &DMatrix<f64>, reference: &DMatrix<f64>) -> f64 {
    let scale = reference.amax().max(f64::MIN_POSITIVE);
    (a - reference).amax() / scale
}
