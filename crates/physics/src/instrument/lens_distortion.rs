//! `lens_distortion` — Brown–Conrady radial + tangential distortion (OpenCV `calibrateCamera`
//! pinhole model, k1 k2 p1 p2 k3; seed 002 eq. 3).
//!
//! For an ideal normalised image point (x, y), r² = x² + y²:
//!   Δx = x·(k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2x²)
//!   Δy = y·(k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2y²) + 2 p2 x y
//! The prediction is distorted − ideal in normalised coordinates (multiply by f_x, f_y for pixels).
//! Not the fisheye (Kannala–Brandt) model. Effect: image shift.

use nalgebra::{DMatrix, DVector};

use crate::term_id::TermId;
use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, ParamSpec, PhysicsTerm, Prediction};

#[derive(Debug, Clone, Default)]
pub struct LensDistortion;

impl LensDistortion {
    pub fn from_options(_o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self)
    }
    fn jac(&self, s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        let q = s.image(&self.label())?;
        let (x, y) = (q.x, q.y);
        let r2 = x * x + y * y;
        // columns: k1, k2, k3, p1, p2
        Ok(DMatrix::from_row_slice(2, 5, &[
            x * r2, x * r2 * r2, x * r2 * r2 * r2, 2.0 * x * y, r2 + 2.0 * x * x,
            y * r2, y * r2 * r2, y * r2 * r2 * r2, r2 + 2.0 * y * y, 2.0 * x * y,
        ]))
    }
}

impl PhysicsTerm for LensDistortion {
    fn id(&self) -> TermId {
        TermId::LensDistortion
    }
    fn label(&self) -> String {
        "lens_distortion".into()
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
        check_len(&self.label(), p, 5)?;
        let v = self.jac(s)? * DVector::from_column_slice(p);
        Ok(Prediction { kind: self.effect(), value: v })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(&self.label(), p, 5)?;
        self.jac(s)
    }
}
