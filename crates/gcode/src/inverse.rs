//! The commanded point that makes the machine reach a target: C + e(C) = T.

use nalgebra::Vector3;

use crate::error_field::{ErrorField, FieldError};

/// How C is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InverseMethod {
    /// Iterate C ← T − e(C) until C moves by less than 1e-12 m: the machine then reaches T to
    /// that precision. Converges when the field's gradient is below 1 (any real machine).
    #[default]
    FixedPoint,
    /// C = T − e(T), one step, as seed 000 applies it; off by about |∇e|·|e|.
    FirstOrder,
}

const MAX_ITERATIONS: usize = 100;
const TOLERANCE_M: f64 = 1e-12;

/// The commanded position (m) for target `target` (m).
pub fn compensate_point(
    field: &dyn ErrorField,
    target: &Vector3<f64>,
    approach: &[f64; 3],
    method: InverseMethod,
) -> Result<Vector3<f64>, FieldError> {
    let mut c = target - field.error(target, approach)?;
    if method == InverseMethod::FirstOrder {
        return Ok(c);
    }
    for _ in 0..MAX_ITERATIONS {
        let next = target - field.error(&c, approach)?;
        let step = (next - c).norm();
        c = next;
        if step < TOLERANCE_M {
            return Ok(c);
        }
    }
    Err(FieldError(format!(
        "the fixed-point iteration C = T − e(C) did not converge in {MAX_ITERATIONS} steps at T = ({:.6}, {:.6}, {:.6}) m: the model's error changes faster than the position there",
        target.x, target.y, target.z
    )))
}
