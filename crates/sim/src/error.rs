//! Errors of the simulator front-end: each names what was wrong and where.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The cell file could not be read or is invalid, or the simulation cannot start.
    #[error(transparent)]
    Cell(#[from] metrocell_twin::CellError),
    /// A command-line or parameter value could not be understood.
    #[error("{what}: {reason}")]
    InvalidArgument { what: String, reason: String },
    /// The bag could not be written.
    #[error("bag {}: {source}", dir.display())]
    Bag {
        dir: PathBuf,
        source: metrocell_bag::BagError,
    },
    /// A message could not be CDR-encoded (not expected for the generated types).
    #[error("CDR encoding of {ros_type} failed: {reason}")]
    Encode {
        ros_type: &'static str,
        reason: String,
    },
    /// The twin's stream stopped early because a physics term failed.
    #[error("simulation stopped at t = {t} s: {reason}")]
    Simulation { t: f64, reason: String },
}

impl SimError {
    pub(crate) fn invalid(what: impl Into<String>, reason: impl Into<String>) -> SimError {
        SimError::InvalidArgument {
            what: what.into(),
            reason: reason.into(),
        }
    }
}
