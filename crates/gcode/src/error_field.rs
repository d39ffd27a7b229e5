//! What the compensator needs of a machine model.

use nalgebra::Vector3;

/// An error that makes a point impossible to compensate (the model cannot be evaluated there,
/// or the fixed-point iteration does not converge).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct FieldError(pub String);

/// Axis-aligned box (m, machine axes) in which a model was calibrated; compensating outside it
/// is extrapolation and is reported. An unbounded axis has infinite limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    pub min: Vector3<f64>,
    pub max: Vector3<f64>,
}

impl Region {
    pub fn contains(&self, p: &Vector3<f64>) -> bool {
        (0..3).all(|k| p[k] >= self.min[k] && p[k] <= self.max[k])
    }
}

/// The error field of a machine: e(C) = reached − commanded at the commanded position C (m,
/// machine axes), for the direction each axis approached C from (+1 or −1, as backlash needs).
pub trait ErrorField {
    fn error(
        &self,
        commanded: &Vector3<f64>,
        approach: &[f64; 3],
    ) -> Result<Vector3<f64>, FieldError>;

    /// Where the model was calibrated, if known.
    fn calibrated_region(&self) -> Option<Region> {
        None
    }
}

/// A machine without errors (e ≡ 0): compensation must leave the program as it is.
#[derive(Debug, Clone, Copy, Default)]
pub struct ZeroField;

impl ErrorField for ZeroField {
    fn error(&self, _: &Vector3<f64>, _: &[f64; 3]) -> Result<Vector3<f64>, FieldError> {
        Ok(Vector3::zeros())
    }
}
