//! What a solve is asked to do: weights, loss, bounds, fixed parameters, priors and tolerances.

use crate::error::{check_finite, check_len, SolverError};
use crate::loss::Loss;

/// A Gaussian prior on one parameter, added as the residual (x[index] − value)/sigma.
/// On a parameter with its own retraction (a manifold state) the prior is applied to the stored
/// coordinate, which is only meaningful for Euclidean parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    pub index: usize,
    pub value: f64,
    pub sigma: f64,
}

/// How steps treat directions the data do not determine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NullSpace {
    /// Ordinary damped steps (the damping keeps the system regular; unidentifiable combinations
    /// drift wherever the damping lets them).
    Damped,
    /// Truncated-SVD steps: directions of the column-scaled normal matrix whose singular value
    /// (√eigenvalue) is below `rcond`·largest are left out, so the solution moves only on the
    /// identifiable subspace and keeps the start's component along the rest (from a start of
    /// zero: the minimum-norm solution in the scaled parameters).
    Truncated { rcond: f64 },
}

/// Solver settings. `Options::default()` is plain least squares with unit weights.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Per-residual standard deviation σᵢ (whitening rᵢ/σᵢ, weight 1/σᵢ²); None: all 1.
    /// Correlated measurements are whitened by the problem itself (multiply its residuals and
    /// Jacobian rows by the inverse Cholesky factor of their covariance).
    pub sigmas: Option<Vec<f64>>,
    pub loss: Loss,
    /// Box bounds (lower, upper), each of length n; ±∞ for unbounded parameters.
    pub bounds: Option<(Vec<f64>, Vec<f64>)>,
    /// `fixed[k]`: parameter k is held at its start value (empty: none fixed).
    pub fixed: Vec<bool>,
    pub priors: Vec<Prior>,
    /// Limit on Jacobian evaluations (outer iterations).
    pub max_iterations: usize,
    /// Stop when an accepted step reduces the cost by less than ftol·cost.
    pub ftol: f64,
    /// Stop when the scaled step ‖D·δ‖ < xtol·(xtol + ‖D·x‖).
    pub xtol: f64,
    /// Stop when every free parameter's residual/column cosine |gₖ|/(‖J̃ₖ‖·‖r̃‖) < gtol.
    pub gtol: f64,
    /// Initial damping λ₀ relative to the scaled normal matrix (unit diagonal).
    pub initial_damping: f64,
    pub null_space: NullSpace,
    /// Evaluate each trial point with its Jacobian (one pass per accepted step instead of two,
    /// at the price of a Jacobian for each rejected one and a second m × n buffer). Set false for
    /// problems whose Jacobian costs much more than their residuals.
    pub jacobian_on_trials: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            sigmas: None,
            loss: Loss::Linear,
            bounds: None,
            fixed: Vec::new(),
            priors: Vec::new(),
            max_iterations: 100,
            ftol: 1e-12,
            xtol: 1e-12,
            gtol: 1e-12,
            initial_damping: 1e-3,
            null_space: NullSpace::Damped,
            jacobian_on_trials: true,
        }
    }
}

impl Options {
    pub(crate) fn validate(&self, m: usize, n: usize) -> Result<(), SolverError> {
        let invalid = |what: &str, reason: String| SolverError::Invalid {
            what: what.into(),
            reason,
        };
        if let Some(s) = &self.sigmas {
            check_len("sigmas", m, s.len())?;
            if let Some(i) = s.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(invalid(
                    &format!("sigmas[{i}]"),
                    format!("must be finite and positive, got {}", s[i]),
                ));
            }
        }
        self.loss.validate()?;
        if let Some((lo, hi)) = &self.bounds {
            check_len("lower bounds", n, lo.len())?;
            check_len("upper bounds", n, hi.len())?;
            for k in 0..n {
                if lo[k].is_nan() || hi[k].is_nan() || lo[k] > hi[k] {
                    return Err(invalid(
                        &format!("bounds[{k}]"),
                        format!("need lower ≤ upper, got [{}, {}]", lo[k], hi[k]),
                    ));
                }
            }
        }
        if !self.fixed.is_empty() {
            check_len("fixed mask", n, self.fixed.len())?;
        }
        for (i, p) in self.priors.iter().enumerate() {
            if p.index >= n {
                return Err(invalid(
                    &format!("priors[{i}]"),
                    format!("parameter index {} ≥ parameter count {n}", p.index),
                ));
            }
            check_finite(&format!("priors[{i}].value"), &[p.value])?;
            if !(p.sigma.is_finite() && p.sigma > 0.0) {
                return Err(invalid(
                    &format!("priors[{i}].sigma"),
                    format!("must be finite and positive, got {}", p.sigma),
                ));
            }
        }
        for (what, v) in [
            ("ftol", self.ftol),
            ("xtol", self.xtol),
            ("gtol", self.gtol),
            ("initial_damping", self.initial_damping),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(invalid(what, format!("must be finite and ≥ 0, got {v}")));
            }
        }
        if let NullSpace::Truncated { rcond } = self.null_space {
            if !(rcond.is_finite() && rcond > 0.0 && rcond < 1.0) {
                return Err(invalid(
                    "null_space rcond",
                    format!("must lie in (0, 1), got {rcond}"),
                ));
            }
        }
        Ok(())
    }

    pub(crate) fn is_fixed(&self, k: usize) -> bool {
        self.fixed.get(k).copied().unwrap_or(false)
    }
}
