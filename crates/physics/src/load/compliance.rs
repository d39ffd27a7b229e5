//! `compliance` — static deflection of a cantilevered structure (ram, arm, extended axis)
//! under a load force F (e.g. payload weight m·g, or probing force).
//!
//! d = F·(c₀ + c_θ·e² + c_b·e³),   e = q_k − e₀ (extension of the cantilever)
//!
//! c₀: translational compliance of the support (m/N); c_θ: rotational compliance of the
//! joint/bearing — a moment F·e tilts it by c_θ·F·e, moving the tip by c_θ·F·e²; c_b: beam
//! bending, e³/(3EI). Each term is proportional to a moment or a power of the extension, so the
//! deflection grows with reach. Frame: machine. Options: `extension_axis`, `extension_origin` (m).

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct Compliance {
    pub extension_axis: Axis,
    pub extension_origin: f64,
}

impl Compliance {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            extension_axis: o.axis("extension_axis", None)?,
            extension_origin: o.quantity("extension_origin", "m", Some(0.0))?,
        })
    }
    fn row(&self, s: &Signals) -> Result<([f64; 3], nalgebra::Vector3<f64>), PhysicsError> {
        let e = s.position(self, self.extension_axis)? - self.extension_origin;
        Ok(([1.0, e * e, e * e * e], s.load(self)?))
    }
}

impl PhysicsTerm for Compliance {
    fn id(&self) -> TermId {
        TermId::Compliance
    }
    fn label(&self) -> String {
        format!("compliance[{}]", self.extension_axis)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::new("translational", "m/N", 0.0, 1e-5, 0.0, "c₀: support compliance").unusual_means("a negative compliance moves against the load: a counterbalance or preload acting, or the load's sign recorded reversed"),
            ParamSpec::new("rotational", "rad/(N m)", 0.0, 1e-5, 0.0, "c_θ: joint compliance (tilt per moment)").unusual_means("a negative compliance moves against the load: a counterbalance or preload acting, or the load's sign recorded reversed"),
            ParamSpec::new("bending", "1/(N m^2)", 0.0, 1e-4, 0.0, "c_b = 1/(3EI): beam bending").unusual_means("a negative compliance moves against the load: a counterbalance or preload acting, or the load's sign recorded reversed"),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![
            SignalKind::AxisPosition(self.extension_axis),
            SignalKind::LoadForce,
        ]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 3)?;
        let (r, f) = self.row(s)?;
        Ok(displacement(
            Frame::Machine,
            f * (r[0] * p[0] + r[1] * p[1] + r[2] * p[2]),
        ))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 3)?;
        let (r, f) = self.row(s)?;
        let mut j = DMatrix::zeros(3, 3);
        for (k, rk) in r.iter().enumerate() {
            j.set_column(k, &(f * *rk));
        }
        Ok(j)
    }
}
