//! Dense Levenberg–Marquardt on a manifold state, shared by calibration and pose refinement.
//!
//! The problem supplies residuals r(s) and their Jacobian with respect to a local perturbation δ
//! of the state, plus the rule s ⊕ δ. Damping is Marquardt's: (JᵀJ + λ·diag(JᵀJ)) δ = −Jᵀr.

use crate::error::{CameraError, Result};
use nalgebra::{DMatrix, DVector};

pub(crate) trait LeastSquares {
    type State: Clone;
    /// Residuals and (if asked) Jacobian at `s`; None if `s` is not evaluable (point behind camera).
    fn evaluate(
        &self,
        s: &Self::State,
        jacobian: bool,
    ) -> Option<(DVector<f64>, Option<DMatrix<f64>>)>;
    fn apply(&self, s: &Self::State, delta: &DVector<f64>) -> Self::State;
}

pub(crate) struct LmOutcome<S> {
    pub state: S,
    pub residuals: DVector<f64>,
    pub jacobian: DMatrix<f64>,
    pub iterations: usize,
}

pub(crate) fn levenberg_marquardt<P: LeastSquares>(
    problem: &P,
    start: P::State,
    max_iterations: usize,
    what: &str,
) -> Result<LmOutcome<P::State>> {
    let fail = |r: &str| CameraError::NoConvergence {
        what: what.into(),
        reason: r.into(),
    };
    let mut s = start;
    let (mut r, j) = problem
        .evaluate(&s, true)
        .ok_or_else(|| fail("initial state not evaluable (points behind the camera)"))?;
    let mut j = j.expect("jacobian requested");
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    let mut iterations = 0;
    for it in 0..max_iterations {
        iterations = it + 1;
        let jt = j.transpose();
        let jtj = &jt * &j;
        let g = &jt * &r;
        if g.amax() < 1e-14 * (1.0 + cost) {
            break;
        }
        let mut improved = false;
        let mut small_step = false;
        for _ in 0..30 {
            let mut a = jtj.clone();
            for k in 0..a.nrows() {
                let d = jtj[(k, k)].max(1e-12);
                a[(k, k)] += lambda * d;
            }
            let delta = match a.cholesky() {
                Some(c) => -c.solve(&g),
                None => {
                    lambda *= 10.0;
                    continue;
                }
            };
            let cand = problem.apply(&s, &delta);
            if let Some((rc, _)) = problem.evaluate(&cand, false) {
                let c = rc.norm_squared();
                if c.is_finite() && c <= cost {
                    let rel = (cost - c) / cost.max(1e-300);
                    small_step = rel < 1e-14 || delta.amax() < 1e-15;
                    s = cand;
                    cost = c;
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = true;
                    break;
                }
            }
            lambda *= 10.0;
            if lambda > 1e16 {
                break;
            }
        }
        let (rn, jn) = problem
            .evaluate(&s, true)
            .ok_or_else(|| fail("state became non-evaluable"))?;
        r = rn;
        j = jn.expect("jacobian requested");
        if !improved || small_step {
            break;
        }
    }
    Ok(LmOutcome {
        state: s,
        residuals: r,
        jacobian: j,
        iterations,
    })
}

/// (JᵀJ)⁻¹ via symmetric eigen-decomposition; None if JᵀJ is rank-deficient (cond > 1e15).
pub(crate) fn normal_inverse(j: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let jtj = j.transpose() * j;
    let eig = nalgebra::SymmetricEigen::new(jtj);
    let max = eig.eigenvalues.amax();
    if !(max > 0.0) || eig.eigenvalues.iter().any(|&l| l <= max * 1e-15) {
        return None;
    }
    let inv_l = DMatrix::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / l));
    Some(&eig.eigenvectors * inv_l * eig.eigenvectors.transpose())
}
