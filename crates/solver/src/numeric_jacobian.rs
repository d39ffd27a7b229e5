//! Central finite differences: the one numeric Jacobian of the workspace, used to check analytic
//! Jacobians and for models without one.

use nalgebra::{DMatrix, DVector};

/// Order of the central-difference formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// (f(x+h) − f(x−h))/2h: truncation error O(h²), 2 evaluations per parameter.
    Second,
    /// (−f(x+2h) + 8f(x+h) − 8f(x−h) + f(x−2h))/12h: O(h⁴), 4 evaluations per parameter.
    Fourth,
}

/// Steps hᵢ = `relative`·max(|xᵢ|, `typical`ᵢ): proportional to the parameter, with a floor at
/// its typical magnitude so that a parameter at zero still gets a step. `relative ≈ 1e-6` balances
/// truncation and rounding for the second order, `≈ 1e-4` for the fourth.
pub fn relative_steps(x: &[f64], relative: f64, typical: &[f64]) -> Vec<f64> {
    x.iter()
        .zip(typical)
        .map(|(v, t)| relative * v.abs().max(*t))
        .collect()
}

/// Steps hᵢ = `relative`·max(|xᵢ|, 1): for parameters of order one (angles in rad, lengths in m).
pub fn steps_with_unit_floor(x: &[f64], relative: f64) -> Vec<f64> {
    x.iter().map(|v| relative * v.abs().max(1.0)).collect()
}

/// Jacobian of `f` at `x` (rows: outputs, columns: parameters) with per-parameter steps
/// `steps` (see [`relative_steps`]). None when `f` fails at a stepped point, when `steps` and `x`
/// differ in length or a step is not finite and positive.
pub fn central_difference<F>(
    mut f: F,
    x: &[f64],
    steps: &[f64],
    order: Order,
) -> Option<DMatrix<f64>>
where
    F: FnMut(&[f64]) -> Option<DVector<f64>>,
{
    if steps.len() != x.len() || steps.iter().any(|h| !(h.is_finite() && *h > 0.0)) {
        return None;
    }
    let mut q = x.to_vec();
    let mut at = |i: usize, k: f64, q: &mut Vec<f64>| {
        q[i] = x[i] + k * steps[i];
        let v = f(q);
        q[i] = x[i];
        v
    };
    let mut columns = Vec::with_capacity(x.len());
    for i in 0..x.len() {
        let h = steps[i];
        let col = match order {
            Order::Second => (at(i, 1.0, &mut q)? - at(i, -1.0, &mut q)?) / (2.0 * h),
            Order::Fourth => {
                let (p2, p1) = (at(i, 2.0, &mut q)?, at(i, 1.0, &mut q)?);
                let (m1, m2) = (at(i, -1.0, &mut q)?, at(i, -2.0, &mut q)?);
                (p1 * 8.0 - m1 * 8.0 - p2 + m2) / (12.0 * h)
            }
        };
        columns.push(col);
    }
    let rows = columns.first().map_or(0, |c| c.len());
    if columns.iter().any(|c| c.len() != rows) {
        return None;
    }
    Some(DMatrix::from_fn(rows, x.len(), |r, c| columns[c][r]))
}

/// Largest element-wise discrepancy between two Jacobians, relative to the largest magnitude in `reference`.
pub fn max_relative_difference(a: &DMatrix<f64>, reference: &DMatrix<f64>) -> f64 {
    let scale = reference.amax().max(f64::MIN_POSITIVE);
    (a - reference).amax() / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_orders_differentiate_a_known_function() {
        // f(x) = (sin x₀ · x₁², exp(x₁)) with J = [[cos x₀·x₁², 2 sin x₀·x₁], [0, exp x₁]].
        let f = |x: &[f64]| {
            Some(DVector::from_column_slice(&[
                x[0].sin() * x[1] * x[1],
                x[1].exp(),
            ]))
        };
        let x = [0.7, -1.3];
        let exact = DMatrix::from_row_slice(
            2,
            2,
            &[
                0.7f64.cos() * 1.69,
                2.0 * 0.7f64.sin() * -1.3,
                0.0,
                (-1.3f64).exp(),
            ],
        );
        let j2 = central_difference(f, &x, &relative_steps(&x, 1e-6, &[1.0, 1.0]), Order::Second)
            .unwrap();
        let j4 = central_difference(f, &x, &relative_steps(&x, 1e-3, &[1.0, 1.0]), Order::Fourth)
            .unwrap();
        assert!(max_relative_difference(&j2, &exact) < 1e-8);
        assert!(max_relative_difference(&j4, &exact) < 1e-11);
        // With the same coarse step the fourth order is far more accurate than the second.
        let coarse = relative_steps(&x, 1e-3, &[1.0, 1.0]);
        let j2c = central_difference(f, &x, &coarse, Order::Second).unwrap();
        assert!(max_relative_difference(&j2c, &exact) > 1e-8);
        assert!(central_difference(|_: &[f64]| None, &x, &coarse, Order::Second).is_none());
        assert!(central_difference(f, &x, &coarse[..1], Order::Second).is_none());
        assert!(central_difference(f, &x, &[1e-6, 0.0], Order::Second).is_none());
    }
}
