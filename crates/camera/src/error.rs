//! Errors of the camera crate. Each variant names what was wrong and where.

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum CameraError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: String, reason: String },
    #[error("point {index}: {reason}")]
    BadPoint { index: usize, reason: String },
    #[error("{what}: need at least {needed} points, got {got}")]
    TooFewPoints {
        what: String,
        needed: usize,
        got: usize,
    },
    #[error("{what}: degenerate configuration ({reason})")]
    Degenerate { what: String, reason: String },
    #[error("{what}: did not converge ({reason})")]
    NoConvergence { what: String, reason: String },
    #[error("calibration: no usable view left ({0})")]
    NoUsableViews(String),
    #[error("camera_info YAML {source_name}: field `{field}`: {reason}")]
    CameraInfo {
        source_name: String,
        field: String,
        reason: String,
    },
    #[error("I/O on {path}: {reason}")]
    Io { path: String, reason: String },
}

pub type Result<T> = std::result::Result<T, CameraError>;

pub(crate) fn invalid(name: &str, reason: impl Into<String>) -> CameraError {
    CameraError::InvalidParameter {
        name: name.to_string(),
        reason: reason.into(),
    }
}
