//! Seed 000's composed planar error field (eq. 7): the first-order Kiridena–Ferreira model of a
//! 3-axis router reduced to its working plane, in the paper's units (mm):
//!
//! ```text
//! e_x = A·X2² + B·X2 + C·X1 + D·X3
//! e_y = E·X1 + F·X2 + G·X3 + H·X1·X2 + I·X1²
//! e_z = 0
//! ```
//!
//! X3 is not the machine's Z: the paper holds it at a constant ("se asumió z = 1") so D and G act
//! as offsets; [`PlanarQuadraticField::x3`] carries that constant.

use nalgebra::Vector3;

use crate::error_field::{ErrorField, FieldError, Region};

/// The nine coefficients A–I of eq. 7 (A, H, I in 1/mm; B, C, E, F in mm/mm; D, G in mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarQuadraticField {
    pub coefficients: [f64; 9],
    /// The constant the paper substitutes for X3 (1 in seed 000).
    pub x3: f64,
    /// Calibrated area (m), if known.
    pub region: Option<Region>,
}

impl PlanarQuadraticField {
    /// Seed 000, Table 2, the 72-row calibration (B72×12), with X3 = 1.
    pub fn seed000_b72() -> Self {
        Self {
            coefficients: [
                1.01e-5, 5.20e-3, -7.10e-3, 4.85e-3, 1.11e-2, 1.03e-2, -1.12e-5, -2.01e-5, -1.55e-5,
            ],
            x3: 1.0,
            region: None,
        }
    }

    /// e (mm) at the commanded position (mm).
    pub fn error_mm(&self, x1: f64, x2: f64) -> (f64, f64) {
        let [a, b, c, d, e, f, g, h, i] = self.coefficients;
        let x3 = self.x3;
        (
            a * x2 * x2 + b * x2 + c * x1 + d * x3,
            e * x1 + f * x2 + g * x3 + h * x1 * x2 + i * x1 * x1,
        )
    }
}

impl ErrorField for PlanarQuadraticField {
    fn error(&self, commanded: &Vector3<f64>, _: &[f64; 3]) -> Result<Vector3<f64>, FieldError> {
        let (ex, ey) = self.error_mm(commanded.x * 1e3, commanded.y * 1e3);
        Ok(Vector3::new(ex * 1e-3, ey * 1e-3, 0.0))
    }

    fn calibrated_region(&self) -> Option<Region> {
        self.region
    }
}
