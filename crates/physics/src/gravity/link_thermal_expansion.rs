//! `link_thermal_expansion` — every link of a robot's chain lengthens with its temperature:
//!
//! Δl_j = α·(T − 20 °C)·l_j,
//!
//! l_j the length of each joint's `<origin xyz>` (URDF) or DH `a`/`d` offset, T the reading of the
//! named sensor (the ambient air where the robot works: links follow it within minutes). To first
//! order the tool point moves by α·(T − 20 °C)·Σ_j ∂p/∂l_j·l_j. Option `sensor`; parameter `alpha`
//! (1/K). Typical: 23 µm/m/K aluminium links, 11.5 steel; outdoors at 9 °C a 1.5 m reach shortens
//! ~0.4 mm. Effect: kinematic.

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct LinkThermalExpansion {
    pub sensor: String,
}

impl LinkThermalExpansion {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            sensor: o.text("sensor", None)?,
        })
    }
}

impl PhysicsTerm for LinkThermalExpansion {
    fn id(&self) -> TermId {
        TermId::LinkThermalExpansion
    }
    fn label(&self) -> String {
        format!("link_thermal_expansion[{}]", self.sensor)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Kinematic
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("alpha", "1/K", 0.0, 30e-6, 0.0, "α of the links (a mix of aluminium and steel)")
            .possible(-100e-6, 100e-6)
            .unusual_means("a negative α shortens the links as they warm: the sensor reads a temperature the links do not follow")]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::Temperature(self.sensor.clone())]
    }
    fn predict(&self, _p: &[f64], _s: &Signals) -> Result<Prediction, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
    fn jacobian(&self, _p: &[f64], _s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
}
