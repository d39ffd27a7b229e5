//! Errors of the physics catalog. Every variant names the term (by id or label) and the
//! parameter, option or signal at fault, so a config file mistake can be found from the message.

use thiserror::Error;

/// Error returned by catalog look-ups, config validation and term evaluation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PhysicsError {
    #[error("unknown term id `{id}`; allowed ids: {allowed}")]
    UnknownTerm { id: String, allowed: String },

    #[error("term `{term}`: missing parameter `{param}` (unit {unit})")]
    MissingParameter {
        term: String,
        param: String,
        unit: String,
    },

    #[error("term `{term}`: unknown parameter `{param}`; allowed parameters: {allowed}")]
    UnknownParameter {
        term: String,
        param: String,
        allowed: String,
    },

    #[error("term `{term}`: parameter `{param}` = {value} {unit} is physically impossible (possible range [{min}, {max}] {unit})")]
    OutOfRange {
        term: String,
        param: String,
        value: f64,
        unit: String,
        min: f64,
        max: f64,
    },

    #[error("term `{term}`: `{key}` is given in `{given}`, which is not a unit of {dimension}; use `{allowed}` (or a scaled form of it)")]
    WrongUnit {
        term: String,
        key: String,
        given: String,
        dimension: String,
        allowed: String,
    },

    #[error("term `{term}`: cannot read `{key}` = `{text}`: {reason}")]
    BadValue {
        term: String,
        key: String,
        text: String,
        reason: String,
    },

    #[error("term `{term}`: option `{key}`: {reason}")]
    BadOption {
        term: String,
        key: String,
        reason: String,
    },

    #[error("term `{term}`: unknown option `{key}`; allowed options: {allowed}")]
    UnknownOption {
        term: String,
        key: String,
        allowed: String,
    },

    #[error("term `{term}` needs signal {signal}, which was not supplied")]
    MissingSignal { term: String, signal: String },

    #[error("term `{term}`: signal {signal} is invalid: {reason}")]
    BadSignal {
        term: String,
        signal: String,
        reason: String,
    },

    #[error("term `{term}` expects {expected} parameter values, got {got}")]
    ParameterCount {
        term: String,
        expected: usize,
        got: usize,
    },

    #[error("term `{term}` is a kinematic term: its prediction needs the machine's kinematic chain (crates/kinematics); evaluate it with `machine_family::predict_through_kinematics`")]
    NeedsKinematics { term: String },

    #[error("{what}: {reason}")]
    InvalidInput { what: String, reason: String },
}
