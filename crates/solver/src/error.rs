//! Errors of the solver: bad input named by what and where, never a panic.

/// What went wrong, with the offending item named.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolverError {
    #[error("{what}: expected {expected} values, got {got}")]
    Length {
        what: String,
        expected: usize,
        got: usize,
    },
    #[error("{what}[{index}] is not finite ({value})")]
    NotFinite {
        what: String,
        index: usize,
        value: f64,
    },
    #[error("{what}: {reason}")]
    Invalid { what: String, reason: String },
    #[error("the problem cannot be evaluated at the start: {0}")]
    StartNotEvaluable(String),
    #[error("the problem cannot be evaluated at the solution: {0}")]
    SolutionNotEvaluable(String),
}

/// The problem cannot be evaluated at a point (a point behind the camera, a joint outside its
/// range, a NaN). The solver rejects such a step and shortens the next one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct NotEvaluable(pub String);

pub(crate) fn check_len(what: &str, expected: usize, got: usize) -> Result<(), SolverError> {
    if expected == got {
        Ok(())
    } else {
        Err(SolverError::Length {
            what: what.into(),
            expected,
            got,
        })
    }
}

pub(crate) fn check_finite(what: &str, v: &[f64]) -> Result<(), SolverError> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(index) => Err(SolverError::NotFinite {
            what: what.into(),
            index,
            value: v[index],
        }),
    }
}
