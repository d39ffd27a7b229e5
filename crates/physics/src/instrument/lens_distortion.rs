//! `lens_distortion` — Brown–Conrady radial + tangential distortion (OpenCV `calibrateCamera`
//! pinhole model, k1 k2 p1 p2 k3; seed 002 eq. 3).
//!
//! For an ideal normalised image point (x, y), r² = x² + y²:
//!   Δx = x·(k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2x²)
//!   Δy = y·(k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2y²) + 2 p2 x y
//! The prediction is distorted − ideal in normalised coordinates (multiply by f_x, f_y for pixels).
//! Not the fisheye (Kannala–Brandt) model. Effect: image shift.

use nalgebra::{DMatrix, DVector};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// ∂(Δx, Δy)/∂(x, y) at the ideal normalised point (x, y) for parameters (k1, k2, k3, p1, p2):
/// with R = k1 r² + k2 r⁴ + k3 r⁶ and R' = dR/d(r²) = k1 + 2 k2 r² + 3 k3 r⁴,
///   ∂Δx/∂x = R + 2x²R' + 2 p1 y + 6 p2 x,   ∂Δx/∂y = 2xyR' + 2 p1 x + 2 p2 y,
///   ∂Δy/∂x = 2xyR' + 2 p1 x + 2 p2 y,       ∂Δy/∂y = R + 2y²R' + 6 p1 y + 2 p2 x.
/// Rows Δx, Δy; columns x, y. (A camera prediction needs it to carry a point's motion through
/// the lens.)
pub fn image_point_jacobian(p: &[f64], x: f64, y: f64) -> [[f64; 2]; 2] {
    let (k1, k2, k3, p1, p2) = (p[0], p[1], p[2], p[3], p[4]);
    let r2 = x * x + y * y;
    let radial = k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
    let slope = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r2 * r2;
    let cross = 2.0 * x * y * slope + 2.0 * p1 * x + 2.0 * p2 * y;
    [
        [
            radial + 2.0 * x * x * slope + 2.0 * p1 * y + 6.0 * p2 * x,
            cross,
        ],
        [
            cross,
            radial + 2.0 * y * y * slope + 6.0 * p1 * y + 2.0 * p2 * x,
        ],
    ]
}

#[derive(Debug, Clone, Default)]
pub struct LensDistortion {
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl LensDistortion {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            instrument: super::instance(o)?,
        })
    }
    fn jac(&self, s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        let q = s.image(self)?;
        let (x, y) = (q.x, q.y);
        let r2 = x * x + y * y;
        // columns: k1, k2, k3, p1, p2
        Ok(DMatrix::from_row_slice(
            2,
            5,
            &[
                x * r2,
                x * r2 * r2,
                x * r2 * r2 * r2,
                2.0 * x * y,
                r2 + 2.0 * x * x,
                y * r2,
                y * r2 * r2,
                y * r2 * r2 * r2,
                r2 + 2.0 * y * y,
                2.0 * x * y,
            ],
        ))
    }
}

impl PhysicsTerm for LensDistortion {
    fn id(&self) -> TermId {
        TermId::LensDistortion
    }
    fn label(&self) -> String {
        super::instance_label("lens_distortion", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::ImageShift
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::new("k1", "1", -2.0, 2.0, 0.0, "radial, r²"),
            ParamSpec::new("k2", "1", -5.0, 5.0, 0.0, "radial, r⁴"),
            ParamSpec::new("k3", "1", -10.0, 10.0, 0.0, "radial, r⁶"),
            ParamSpec::new("p1", "1", -0.05, 0.05, 0.0, "tangential 1"),
            ParamSpec::new("p2", "1", -0.05, 0.05, 0.0, "tangential 2"),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::ImagePoint]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 5)?;
        let v = self.jac(s)? * DVector::from_column_slice(p);
        Ok(Prediction {
            kind: self.effect(),
            value: v,
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 5)?;
        self.jac(s)
    }
}
