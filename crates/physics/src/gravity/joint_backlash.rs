//! `joint_backlash` — a robot joint's play taken up to the side gravity pushes it:
//!
//! Δθ_j = (b_j/2)·sign(τ_j),
//!
//! b_j the joint's whole play (rad; the commanded angle sits in its middle), τ_j the gravity torque on
//! it (see [`super`]). Where the torque changes sign between two poses the joint jumps by b_j — what
//! a rigid model cannot follow. Typical: 0.05–0.5 mrad on a harmonic or cycloidal gearbox. Option
//! `joints`; parameters `b_<joint>`. Effect: kinematic.

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct JointBacklash {
    pub joints: Vec<String>,
}

impl JointBacklash {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            joints: super::joint_names(o)?,
        })
    }
}

impl PhysicsTerm for JointBacklash {
    fn id(&self) -> TermId {
        TermId::JointBacklash
    }
    fn label(&self) -> String {
        "joint_backlash".into()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Kinematic
    }
    fn params(&self) -> Vec<ParamSpec> {
        self.joints
            .iter()
            .map(|j| {
                ParamSpec::new(format!("b_{j}"), "rad", 0.0, 1e-3, 0.0, format!("play of joint {j}, taken up to the side of the gravity torque"))
                    .unusual_means("a negative play moves the joint against the torque: a preload or the controller's backlash compensation set too high")
            })
            .collect()
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::Gravity]
    }
    fn predict(&self, _p: &[f64], _s: &Signals) -> Result<Prediction, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
    fn jacobian(&self, _p: &[f64], _s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
}
