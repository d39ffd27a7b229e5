//! The interface a least-squares problem implements.

use crate::error::NotEvaluable;
use nalgebra::DMatrix;

/// A nonlinear least-squares problem: minimise ½·Σ ρ(rᵢ(x)²) over the parameters x.
///
/// Residuals and the Jacobian are written into buffers the solver allocates once per solve, so an
/// iteration allocates nothing on the problem's side. The Jacobian is ∂r/∂δ at x, where δ is the
/// step applied by [`Problem::retract`]: for ordinary (Euclidean) parameters δ is just x' − x; a
/// problem whose state lives on a manifold (a rotation stored as a rotation vector, say) defines its
/// own retraction and differentiates with respect to the local perturbation it applies.
pub trait Problem {
    /// Number of residuals m.
    fn residual_count(&self) -> usize;
    /// Number of parameters n (the length of x and of a step δ).
    fn parameter_count(&self) -> usize;
    /// r(x) into `residuals` (length m).
    fn residuals(&self, x: &[f64], residuals: &mut [f64]) -> Result<(), NotEvaluable>;
    /// r(x) into `residuals` and ∂r/∂δ into `jacobian` (m × n, every entry written).
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable>;
    /// [`Self::residuals_and_jacobian`], except that columns k with `!wanted[k]` may be left
    /// unwritten (the solver passes its free mask: it never reads a fixed parameter's column).
    /// Writing m × n entries is a fair part of evaluating a large problem; a problem that can
    /// skip columns overrides this. The default writes every column.
    fn residuals_and_jacobian_of(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: &mut DMatrix<f64>,
        wanted: &[bool],
    ) -> Result<(), NotEvaluable> {
        let _ = wanted;
        self.residuals_and_jacobian(x, residuals, jacobian)
    }
    /// x ⊕ δ into `out`; the default is x + δ.
    fn retract(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        for ((o, a), d) in out.iter_mut().zip(x).zip(delta) {
            *o = a + d;
        }
    }
}
