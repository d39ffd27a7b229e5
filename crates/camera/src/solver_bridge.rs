//! How the camera's fits call the workspace solver: pixel residuals, unit weights, tight
//! tolerances, and the solver's errors as camera errors.

use crate::error::{CameraError, Result};
use metrocell_solver::{solve, NotEvaluable, Options, Problem, Solution};

/// A projection that failed (point behind the camera) makes the trial point unusable.
pub(crate) fn not_evaluable(e: CameraError) -> NotEvaluable {
    NotEvaluable(e.to_string())
}

/// Levenberg–Marquardt from `x0` to round-off (relative tolerances 1e-14) or `max_iterations`.
pub(crate) fn solve_pixels<P: Problem>(
    problem: &P,
    x0: &[f64],
    max_iterations: usize,
    what: &str,
) -> Result<Solution> {
    let options = Options {
        max_iterations,
        ftol: 1e-14,
        xtol: 1e-14,
        gtol: 1e-14,
        ..Options::default()
    };
    solve(problem, x0, &options).map_err(|e| CameraError::NoConvergence {
        what: what.into(),
        reason: e.to_string(),
    })
}
