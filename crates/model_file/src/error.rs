//! Errors of a cell file, read as a model (this crate) or as a cell to simulate (crates/twin).
//! Every variant names where in the cell file the problem is (a dotted path such as
//! `sensors.tracker.range_noise.constant` or `terms[2]`) and, where there is a closed set, the
//! allowed values.

use metrocell_physics::PhysicsError;
use thiserror::Error;

/// Error loading or validating a cell description, or starting a simulation (the twin's
/// `Simulation` variant).
#[derive(Debug, Error)]
pub enum CellError {
    #[error("cannot read cell file `{file}`: {reason}")]
    Io { file: String, reason: String },

    /// Syntax or schema error reported by the YAML reader (unknown key, wrong type, unknown
    /// variant); serde's message names the key and lists the expected ones.
    #[error("cell file `{file}`: {message}")]
    Yaml { file: String, message: String },

    /// A physics term (or a sensor model built from a physics term) was rejected by the
    /// physics catalog's validation.
    #[error("cell file: `{path}`: {source}")]
    Term {
        path: String,
        source: Box<PhysicsError>,
    },

    #[error("cell file: `{path}` = `{text}`: {reason}")]
    BadQuantity {
        path: String,
        text: String,
        reason: String,
    },

    #[error("cell file: `{path}` is given in `{given}`, which is not a unit of {dimension}; use `{allowed}` (or a scaled form of it)")]
    WrongUnit {
        path: String,
        given: String,
        dimension: String,
        allowed: String,
    },

    #[error("cell file: `{path}` = {value} is out of range: {reason}")]
    OutOfRange {
        path: String,
        value: f64,
        reason: String,
    },

    #[error("cell file: `{path}`: {reason}")]
    Invalid { path: String, reason: String },

    /// An error in a named file (the model loader wraps its validation errors in it). The inner
    /// error is part of this one's message, not a separate `source` (a chain printer would say
    /// it twice).
    #[error("{file}: {error}")]
    InFile { file: String, error: Box<CellError> },

    #[error("simulation: {reason}")]
    Simulation { reason: String },
}

impl CellError {
    pub fn invalid(path: impl Into<String>, reason: impl Into<String>) -> Self {
        CellError::Invalid {
            path: path.into(),
            reason: reason.into(),
        }
    }
    pub fn term(path: impl Into<String>, source: PhysicsError) -> Self {
        CellError::Term {
            path: path.into(),
            source: Box::new(source),
        }
    }
}
