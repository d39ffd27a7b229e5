//! What a solve returns: the estimate, how the iteration ended, and its uncertainty.

use crate::error::SolverError;
use crate::identifiability::Identifiability;
use nalgebra::DMatrix;

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// gtol: every free column of J̃ is orthogonal to the residuals within gtol (or the cost is 0).
    Gradient,
    /// ftol: an accepted step reduced the cost by less than ftol·cost.
    Cost,
    /// xtol: the scaled step fell below xtol·(xtol + ‖D·x‖).
    Step,
    /// The iteration limit was reached first: the estimate may not be converged.
    MaxIterations,
    /// No damping up to the limit gave a cost decrease: x is a minimum to round-off, or the
    /// problem's Jacobian is wrong.
    NoDescent,
}

impl Termination {
    /// Whether the reason is a convergence test (not a limit or a failure).
    pub fn converged(&self) -> bool {
        matches!(
            self,
            Termination::Gradient | Termination::Cost | Termination::Step
        )
    }

    /// Why the iteration stopped, in words a person reads after "fitted in 0.9 s (3 iterations; …)".
    pub fn in_words(&self) -> &'static str {
        match self {
            Termination::Gradient => "converged: no direction lowers the cost further",
            Termination::Cost => {
                "converged: the last step lowered the cost by a negligible fraction"
            }
            Termination::Step => "converged: the last step was negligible",
            Termination::MaxIterations => {
                "stopped at the iteration limit: the estimate may not be converged"
            }
            Termination::NoDescent => "stopped: no step lowered the cost (a minimum to round-off)",
        }
    }
}

/// The result of [`crate::solve`]. Residual-space quantities (cost, weights) are those of the
/// whitened residuals r̃ᵢ = rᵢ/σᵢ.
#[derive(Debug, Clone)]
pub struct Solution {
    pub x: Vec<f64>,
    /// ½·Σ ρ(r̃ᵢ²) + ½·Σ ((xₖ − priorₖ)/σₖ)² at x.
    pub cost: f64,
    /// Jacobian evaluations after the start (outer iterations).
    pub iterations: usize,
    /// Residual evaluations, the start included.
    pub evaluations: usize,
    pub termination: Termination,
    /// The damping λ at the end (relative to the column-scaled normal matrix).
    pub damping: f64,
    /// r(x) as the problem returns it (unwhitened).
    pub residuals: Vec<f64>,
    /// √(Σ rᵢ²/m), in the residuals' units.
    pub residual_rms: f64,
    /// Observations (residuals not down-weighted + priors) minus free parameters.
    pub degrees_of_freedom: usize,
    /// A-posteriori variance factor σ̂₀² = r̂ᵀWr̂/(n − p), W the whitening, over the residuals
    /// the loss keeps quadratic (all for the linear loss; the down-weighted ones are left out of
    /// both the sum and n) and the priors; None with no redundancy.
    pub variance_factor: Option<f64>,
    /// (J̃ᵀWJ̃ + priors)⁻¹ on the free parameters, zero rows and columns for fixed ones: the
    /// covariance if the σᵢ given are right. None if the free parameters are not all
    /// identifiable (see [`Solution::identifiability`]).
    pub covariance_unscaled: Option<DMatrix<f64>>,
    /// Residuals beyond the robust loss's scale (|r̃ᵢ| > c) at the solution: the measurements it
    /// down-weighted. 0 for the linear loss.
    pub downweighted: usize,
    /// √W·J at the solution (m × n; the columns of fixed parameters zero), for the
    /// identifiability analysis.
    pub weighted_jacobian: DMatrix<f64>,
    /// (√W·J)ᵀ(√W·J) at the solution (n × n; zero in the rows and columns of fixed parameters;
    /// priors not included).
    pub normal_matrix: DMatrix<f64>,
    /// Parameters that were estimated (not fixed).
    pub free: Vec<bool>,
}

impl Solution {
    /// Parameter covariance (J̃ᵀWJ̃)⁻¹·σ̂₀²: the unscaled covariance rescaled by how well the
    /// residuals agree with the σᵢ given.
    pub fn covariance(&self) -> Option<DMatrix<f64>> {
        Some(self.covariance_unscaled.as_ref()? * self.variance_factor?)
    }

    /// Standard uncertainties √diag of [`Solution::covariance`] (0 for fixed parameters).
    pub fn standard_uncertainties(&self) -> Option<Vec<f64>> {
        let c = self.covariance()?;
        Some((0..c.nrows()).map(|k| c[(k, k)].max(0.0).sqrt()).collect())
    }

    /// Correlation matrix of the free parameters (0 rows/columns and 1 on the diagonal for fixed ones).
    pub fn correlations(&self) -> Option<DMatrix<f64>> {
        let c = self.covariance_unscaled.as_ref()?;
        let n = c.nrows();
        Some(DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                1.0
            } else if self.free[i] && self.free[j] {
                c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt()
            } else {
                0.0
            }
        }))
    }

    /// SVD of the weighted, column-scaled Jacobian of the free parameters (priors not included:
    /// what the measurements alone determine). `labels` name all n parameters; `rcond` as in
    /// [`Identifiability::analyze`] (from `rcond` ≥ [`crate::identifiability::GRAM_RCOND`] on,
    /// from the normal matrix the solver formed, with no pass over the Jacobian).
    pub fn identifiability(
        &self,
        labels: &[&str],
        rcond: Option<f64>,
    ) -> Result<Identifiability, SolverError> {
        crate::error::check_len("parameter labels", self.free.len(), labels.len())?;
        let idx: Vec<usize> = (0..self.free.len()).filter(|&k| self.free[k]).collect();
        let names: Vec<&str> = idx.iter().map(|&k| labels[k]).collect();
        match rcond {
            Some(r) if r >= crate::identifiability::GRAM_RCOND => {
                let normal = self.normal_matrix.select_rows(&idx).select_columns(&idx);
                Identifiability::from_normal_matrix(
                    &normal,
                    self.weighted_jacobian.nrows(),
                    &names,
                    r,
                )
            }
            _ => Identifiability::analyze(
                &self.weighted_jacobian.select_columns(&idx),
                &names,
                rcond,
            ),
        }
    }
}
