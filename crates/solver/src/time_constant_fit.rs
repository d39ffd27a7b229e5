//! The separable fit of a time constant: y(t) = c + g·x(t; τ), linear in the offset c and the
//! coefficient g for a given τ. The one implementation of the workspace, used by the tracker's
//! warm-up fit (x = 1 − e^(−t/τ)) and the thermal growth fit (x = lagged temperature − T_ref).
//!
//! Method: for each τ a weighted linear fit of (c, g) gives χ²(τ); χ² is minimised over ln τ by
//! a log-spaced scan of the caller's range, then golden-section search on the scan cells either
//! side of its best point. The covariance of (c, g, τ) is the Gauss–Newton inverse at the
//! optimum, (JᵀWJ)⁻¹ with J = [1, x, g·∂x/∂τ], scaled by the caller's [`ChiSquareScaling`].
//!
//! # χ² scaling (the one rule, stated here)
//! The reduced χ², χ²/(n − 3), says how the residuals scatter against the variances given.
//! - [`ChiSquareScaling::StatedVariances`]: the variances are the full, known noise of y (an
//!   instrument's stated σ). The covariance is scaled by max(χ²/dof, 1) (Birge ratio): inflated
//!   when the data scatter more than stated (the model misses something), never shrunk below what
//!   the stated σ supports (a lucky low χ² is not evidence of a better instrument).
//! - [`ChiSquareScaling::RelativeVariances`]: the variances are weights whose level is not known
//!   (y carries noise the caller cannot state, e.g. propagated through a model); the noise level
//!   is estimated from the scatter and the covariance scaled by χ²/dof, up or down.
//!
//! With no degree of freedom left (n = 3) the covariance is not scaled.

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

/// One observation at a trial τ: the regressor x(t; τ), its derivative ∂x/∂τ, the observed y and
/// its variance (units of y²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeConstantRow {
    pub x: f64,
    pub dx_dtau: f64,
    pub y: f64,
    pub variance: f64,
}

/// What the caller's variances are; see the module doc for the rule each implies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChiSquareScaling {
    /// Known, complete noise of y: scale by max(χ²/dof, 1).
    StatedVariances,
    /// Relative weights, the noise level estimated from the scatter: scale by χ²/dof.
    RelativeVariances,
}

impl ChiSquareScaling {
    /// The factor applied to (JᵀWJ)⁻¹ for χ² over `dof` degrees of freedom (1 when dof = 0).
    pub fn factor(self, chi2: f64, dof: usize) -> f64 {
        if dof == 0 {
            return 1.0;
        }
        let reduced = chi2 / dof as f64;
        match self {
            ChiSquareScaling::StatedVariances => reduced.max(1.0),
            ChiSquareScaling::RelativeVariances => reduced,
        }
    }
}

/// Where τ is searched and how the covariance is scaled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeConstantSearch {
    /// (τ_min, τ_max), same unit as the caller's times; 0 < τ_min < τ_max.
    pub range: (f64, f64),
    /// Points of the log-spaced scan, ends included (≥ 3).
    pub scan_points: usize,
    pub scaling: ChiSquareScaling,
}

/// The fit of (c, g, τ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeConstantFit {
    /// c, unit of y
    pub offset: f64,
    /// g, unit of y per unit of x
    pub coefficient: f64,
    pub tau: f64,
    /// Covariance of (c, g, τ), scaled by the search's rule.
    pub covariance: Matrix3<f64>,
    /// Σ (residual / σ)² at the optimum.
    pub chi2: f64,
    /// n − 3 (0 when n = 3).
    pub dof: usize,
    /// Root mean square of the unweighted residuals, unit of y.
    pub rms: f64,
    /// Rows at the optimum.
    pub rows: usize,
    /// The best scan point was an end of the range: the data do not pin τ down inside it.
    pub at_bound: bool,
}

/// Why there is no fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeConstantFitError {
    /// The search's range or scan is not usable (0 < τ_min < τ_max, ≥ 3 scan points).
    BadSearch,
    /// Fewer than 3 rows: (c, g, τ) cannot be determined.
    TooFewRows(usize),
    /// (c, g) is singular at every τ: x does not vary.
    NoVariation,
    /// The Gauss–Newton matrix is singular at the optimum: y does not depend on τ.
    TauUndetermined,
}

/// Weighted linear fit of (c, g) over `rows`: (c, g, χ²); None when x does not vary.
fn linear_fit(rows: &[TimeConstantRow]) -> Option<(f64, f64, f64)> {
    let mut n = Matrix2::zeros();
    let mut b = Vector2::zeros();
    for r in rows {
        let w = 1.0 / r.variance;
        let j = Vector2::new(1.0, r.x);
        n += j * j.transpose() * w;
        b += j * (w * r.y);
    }
    let sol = n.try_inverse()? * b;
    let chi2 = rows
        .iter()
        .map(|r| (r.y - sol[0] - sol[1] * r.x).powi(2) / r.variance)
        .sum();
    Some((sol[0], sol[1], chi2))
}

/// Golden-section steps on the two scan cells around the best point: each shrinks the bracket by
/// 0.618, so 60 leave it at 3e-13 of a cell, far below what χ² resolves.
const GOLDEN_STEPS: usize = 60;

/// ln τ minimising χ²(τ) (scan then golden section) and whether the scan's best was at an end.
fn minimise_ln_tau(chi2: &dyn Fn(f64) -> f64, search: &TimeConstantSearch) -> (f64, bool, f64) {
    let points = search.scan_points;
    let (lo, hi) = (search.range.0.ln(), search.range.1.ln());
    let grid: Vec<f64> = (0..points)
        .map(|i| lo + (hi - lo) * i as f64 / (points - 1) as f64)
        .collect();
    let values: Vec<f64> = grid.iter().map(|&g| chi2(g)).collect();
    let best = (0..points)
        .min_by(|&a, &b| values[a].total_cmp(&values[b]))
        .unwrap_or(0);
    let (mut a, mut b) = (
        grid[best.saturating_sub(1)],
        grid[(best + 1).min(points - 1)],
    );
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (b - r * (b - a), a + r * (b - a));
    let (mut f1, mut f2) = (chi2(x1), chi2(x2));
    for _ in 0..GOLDEN_STEPS {
        if f1 < f2 {
            (b, x2, f2) = (x2, x1, f1);
            x1 = b - r * (b - a);
            f1 = chi2(x1);
        } else {
            (a, x1, f1) = (x1, x2, f2);
            x2 = a + r * (b - a);
            f2 = chi2(x2);
        }
    }
    let golden = if f1 < f2 { x1 } else { x2 };
    let ln_tau = if values[best] < f1.min(f2) {
        grid[best]
    } else {
        golden
    };
    (ln_tau, best == 0 || best == points - 1, values[best])
}

/// Fit (c, g, τ) to the rows that `rows_at(τ)` gives for each trial τ (the regressor depends on
/// τ; the rows may differ in number between τs, e.g. when a lag has no output yet).
pub fn fit_time_constant(
    rows_at: &dyn Fn(f64) -> Vec<TimeConstantRow>,
    search: &TimeConstantSearch,
) -> Result<TimeConstantFit, TimeConstantFitError> {
    let (lo, hi) = search.range;
    if !(lo > 0.0 && hi > lo && hi.is_finite() && search.scan_points >= 3) {
        return Err(TimeConstantFitError::BadSearch);
    }
    let chi2 = |ln_tau: f64| linear_fit(&rows_at(ln_tau.exp())).map_or(f64::INFINITY, |f| f.2);
    let (ln_tau, at_bound, best_scan) = minimise_ln_tau(&chi2, search);
    if !best_scan.is_finite() {
        return Err(TimeConstantFitError::NoVariation);
    }
    let tau = ln_tau.exp();
    let rows = rows_at(tau);
    if rows.len() < 3 {
        return Err(TimeConstantFitError::TooFewRows(rows.len()));
    }
    let (c, g, chi2_min) = linear_fit(&rows).ok_or(TimeConstantFitError::NoVariation)?;
    let mut normal = Matrix3::zeros();
    for r in &rows {
        let j = Vector3::new(1.0, r.x, g * r.dx_dtau);
        normal += j * j.transpose() / r.variance;
    }
    let dof = rows.len() - 3;
    let covariance = normal
        .try_inverse()
        .ok_or(TimeConstantFitError::TauUndetermined)?
        * search.scaling.factor(chi2_min, dof);
    let rms = (rows
        .iter()
        .map(|r| (r.y - c - g * r.x).powi(2))
        .sum::<f64>()
        / rows.len() as f64)
        .sqrt();
    Ok(TimeConstantFit {
        offset: c,
        coefficient: g,
        tau,
        covariance,
        chi2: chi2_min,
        dof,
        rms,
        rows: rows.len(),
        at_bound,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = c + g·(1 − e^(−t/τ)) sampled without noise, with alternating ±σ offsets so χ² is known.
    fn rows(tau: f64, wiggle: f64) -> impl Fn(f64) -> Vec<TimeConstantRow> {
        move |trial: f64| {
            (1..=40)
                .map(|k| {
                    let t = 60.0 * k as f64;
                    let truth = 2.0 + 0.5 * (1.0 - (-t / tau).exp());
                    let e = (-t / trial).exp();
                    TimeConstantRow {
                        x: 1.0 - e,
                        dx_dtau: -t / (trial * trial) * e,
                        y: truth + if k % 2 == 0 { wiggle } else { -wiggle },
                        variance: 1e-4,
                    }
                })
                .collect()
        }
    }

    fn search(scaling: ChiSquareScaling) -> TimeConstantSearch {
        TimeConstantSearch {
            range: (10.0, 1e5),
            scan_points: 60,
            scaling,
        }
    }

    #[test]
    fn noise_free_rows_give_the_truth() {
        let f = fit_time_constant(
            &rows(600.0, 0.0),
            &search(ChiSquareScaling::StatedVariances),
        )
        .unwrap();
        assert!((f.tau - 600.0).abs() < 1e-4, "τ {}", f.tau);
        assert!((f.offset - 2.0).abs() < 1e-9 && (f.coefficient - 0.5).abs() < 1e-9);
        assert!(!f.at_bound && f.rows == 40 && f.dof == 37);
    }

    #[test]
    fn stated_variances_are_never_shrunk_and_relative_ones_follow_the_scatter() {
        // scatter of 0.1 σ: χ²/dof ≈ 0.01
        let quiet = rows(600.0, 1e-3);
        let stated = fit_time_constant(&quiet, &search(ChiSquareScaling::StatedVariances)).unwrap();
        let relative =
            fit_time_constant(&quiet, &search(ChiSquareScaling::RelativeVariances)).unwrap();
        let reduced = stated.chi2 / stated.dof as f64;
        assert!(reduced < 0.02, "χ²/dof {reduced}");
        let ratio = relative.covariance[(2, 2)] / stated.covariance[(2, 2)];
        assert!(
            (ratio - reduced).abs() < 1e-9 * reduced,
            "{ratio} vs {reduced}"
        );
        // scatter of 3 σ: both inflate by χ²/dof ≈ 9
        let loud = rows(600.0, 3e-2);
        let s = fit_time_constant(&loud, &search(ChiSquareScaling::StatedVariances)).unwrap();
        let r = fit_time_constant(&loud, &search(ChiSquareScaling::RelativeVariances)).unwrap();
        assert!(s.chi2 / s.dof as f64 > 8.0);
        assert_eq!(s.covariance, r.covariance);
        assert_eq!(ChiSquareScaling::StatedVariances.factor(5.0, 0), 1.0);
        assert_eq!(ChiSquareScaling::RelativeVariances.factor(5.0, 10), 0.5);
        assert_eq!(ChiSquareScaling::StatedVariances.factor(5.0, 10), 1.0);
    }

    #[test]
    fn unusable_inputs_are_named() {
        let flat = |_: f64| {
            vec![
                TimeConstantRow {
                    x: 0.0,
                    dx_dtau: 0.0,
                    y: 1.0,
                    variance: 1.0
                };
                5
            ]
        };
        let s = search(ChiSquareScaling::StatedVariances);
        assert_eq!(
            fit_time_constant(&flat, &s),
            Err(TimeConstantFitError::NoVariation)
        );
        let bad = TimeConstantSearch {
            range: (10.0, 5.0),
            ..s
        };
        assert_eq!(
            fit_time_constant(&rows(600.0, 0.0), &bad),
            Err(TimeConstantFitError::BadSearch)
        );
    }
}
