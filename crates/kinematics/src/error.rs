//! The one error type of this crate: every variant names what was wrong and where.

use thiserror::Error;

/// Errors returned for bad input or for geometry with no solution.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum KinematicsError {
    /// A Cartesian stacking string such as `XFYZ` was malformed.
    #[error("stacking order `{order}`: {reason}")]
    StackingOrder { order: String, reason: String },
    /// A numeric input was not finite or outside its valid domain.
    #[error("invalid value for `{field}`: {value} ({reason})")]
    InvalidValue {
        field: String,
        value: f64,
        reason: String,
    },
    /// A vector or table had the wrong length.
    #[error("`{field}` has length {got}, expected {expected}")]
    LengthMismatch {
        field: String,
        got: usize,
        expected: usize,
    },
    /// A delta tower cannot reach the requested effector position (rod shorter than the horizontal distance).
    #[error("delta tower {tower}: effector at horizontal distance {horizontal_distance} m exceeds rod length {rod_length} m")]
    DeltaUnreachable {
        tower: usize,
        horizontal_distance: f64,
        rod_length: f64,
    },
    /// The three delta rod spheres do not intersect for the given carriage heights.
    #[error("delta forward kinematics: carriage heights {heights:?} m give no common point (spheres do not intersect)")]
    DeltaNoIntersection { heights: [f64; 3] },
    /// Two or more delta towers coincide in plan, so trilateration is undefined.
    #[error("delta geometry degenerate: {reason}")]
    DeltaDegenerate { reason: String },
    /// An inverse-kinematics request has no solution within the machine's limits.
    #[error("inverse kinematics for {machine}: {reason}")]
    NoSolution { machine: String, reason: String },
    /// A URDF document could not be read or describes something unsupported.
    #[error("URDF: {reason}")]
    Urdf { reason: String },
    /// A geometric configuration for frame alignment is degenerate (would divide by ~0).
    #[error("frame alignment degenerate: {reason}")]
    Degenerate { reason: String },

    /// The robot or camera an alignment drives failed (no answer, a refused move, no reading).
    #[error("alignment rig: {reason}")]
    Rig { reason: String },
}

pub(crate) fn check_finite(field: &str, value: f64) -> Result<f64, KinematicsError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(KinematicsError::InvalidValue {
            field: field.to_string(),
            value,
            reason: "not finite".into(),
        })
    }
}
