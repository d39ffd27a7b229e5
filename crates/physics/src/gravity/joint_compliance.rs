//! `joint_compliance` — a robot joint yields to the gravity torque about it:
//!
//! Δθ_j = k_j·τ_j,
//!
//! τ_j the gravity torque on joint j (see [`super`]: the generalised force, N·m), k_j its angular
//! compliance (rad/(N·m): the gearbox's and the link's torsion). The joint's true value is the
//! commanded one plus Δθ_j; everything outboard turns with it. Typical: 1–20 µrad/(N·m) for the
//! shoulder and elbow of a 10-kg-payload arm (a 150 N·m shoulder torque then sags it 1–3 mrad).
//! Option `joints`: the joints it acts on (revolute, by their URDF names); parameters `k_<joint>`.
//! Effect: kinematic (crates/model applies it through the chain).

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct JointCompliance {
    pub joints: Vec<String>,
}

impl JointCompliance {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            joints: super::joint_names(o)?,
        })
    }
}

impl PhysicsTerm for JointCompliance {
    fn id(&self) -> TermId {
        TermId::JointCompliance
    }
    fn label(&self) -> String {
        "joint_compliance".into()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Kinematic
    }
    fn params(&self) -> Vec<ParamSpec> {
        self.joints
            .iter()
            .map(|j| {
                ParamSpec::new(format!("k_{j}"), "rad/(N m)", 0.0, 5e-5, 0.0, format!("angular compliance of joint {j}: its deflection per N·m of gravity torque"))
                    .unusual_means("a negative compliance turns the joint against the torque (a counterbalance spring or a gravity compensation in the controller acting, or the joint's axis sense in the URDF reversed); a larger one than usual is a worn gearbox or a tool heavier than the URDF says")
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
