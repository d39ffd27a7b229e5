//! `workpiece_expansion` — thermal expansion of a workpiece or artefact about its clamp point
//! (thesis P2/P4 plate correction, clamp at (200, 250) mm, α_plate = 24·10⁻⁶ /K).
//!
//! d = α·(T_w − T_ref)·(p − c)
//!
//! p = nominal feature position (signal `workpiece_point`), c = clamp point (option `clamp`, m), T_w the
//! workpiece sensor (option `sensor`), T_ref = 20 °C. The correction back to 20 °C is
//! d_f = d₀·(1 − α(T − 20)) to first order (P2 eq. 2); see [`corrected_distance`].
//! Frame: workpiece.

use nalgebra::{DMatrix, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// Distance from the clamp point referred back to T_ref (thesis P2 eq. 2):
/// d_f = d₀·(1 + α·(T_ref − T)).
pub fn corrected_distance(d0: f64, alpha: f64, temperature: f64, reference: f64) -> f64 {
    d0 * (1.0 + alpha * (reference - temperature))
}

#[derive(Debug, Clone)]
pub struct WorkpieceExpansion {
    pub clamp: Vector3<f64>,
    pub sensor: String,
    pub reference_temperature: f64,
}

impl WorkpieceExpansion {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            clamp: o.vector3("clamp", "m", Some(Vector3::zeros()))?,
            sensor: o.text("sensor", None)?,
            reference_temperature: o.quantity("reference_temperature", "degC", Some(20.0))?,
        })
    }
    fn lever(&self, s: &Signals) -> Result<Vector3<f64>, PhysicsError> {
        Ok((s.workpiece(self)? - self.clamp)
            * (s.temperature(self, &self.sensor)? - self.reference_temperature))
    }
}

impl PhysicsTerm for WorkpieceExpansion {
    fn id(&self) -> TermId {
        TermId::WorkpieceExpansion
    }
    fn label(&self) -> String {
        format!("workpiece_expansion[{}]", self.sensor)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Workpiece)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("alpha", "1/K", -2e-6, 30e-6, 11.5e-6, "α: expansion coefficient of the workpiece material")
            .possible(-100e-6, 100e-6)
            .unusual_means("outside −2 … 30 µm/m/K the part is not at the temperature its sensor reads, or the material is not a metal (polymers reach 50–200 µm/m/K)")]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![
            SignalKind::WorkpiecePoint,
            SignalKind::Temperature(self.sensor.clone()),
        ]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(displacement(Frame::Workpiece, self.lever(s)? * p[0]))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(DMatrix::from_column_slice(3, 1, self.lever(s)?.as_slice()))
    }
}
