//! Errors returned by this crate. Each variant names what was wrong and where.

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum VisionError {
    #[error("unknown ArUco dictionary name `{0}` (expected an OpenCV name such as DICT_4X4_50)")]
    UnknownDictionary(String),
    #[error("marker id {id} out of range: dictionary {dictionary} has {count} markers")]
    MarkerIdOutOfRange {
        dictionary: &'static str,
        id: usize,
        count: usize,
    },
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error("image {what} is empty or too small ({width}x{height})")]
    ImageTooSmall {
        what: &'static str,
        width: u32,
        height: u32,
    },
    #[error("point {index} of `{what}` is not finite")]
    NonFinite { what: &'static str, index: usize },
    #[error("{what}: no solution ({reason})")]
    NoSolution { what: &'static str, reason: String },
}

pub type Result<T> = std::result::Result<T, VisionError>;

/// Helper for parameter checks.
pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> VisionError {
    VisionError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}
