//! Kinematic terms: `delta_rod_length`, `delta_radius`, `delta_tower_angle`, `delta_endstop`,
//! `joint_offset`, `link_length`.
//!
//! These are **parameter carriers**: they perturb parameters of a kinematic chain (Marlin-style
//! delta geometry, or a serial arm's DH/URDF joints), so their effect on the tool point needs the
//! forward kinematics, which live in crates/kinematics. Their `predict`/`jacobian` return
//! [`PhysicsError::NeedsKinematics`]; evaluate them with [`predict_through_kinematics`], which
//! takes the forward kinematics as a closure and differentiates it numerically (central
//! differences).
//!
//! Per-tower parameters (delta) are ordered A, B, C = Marlin's towers at 210°, 330°, 90°.

use metrocell_solver::numeric_jacobian::{central_difference, relative_steps, Order};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// A kinematic-chain parameter carrier.
#[derive(Debug, Clone)]
pub struct KinematicParameters {
    pub id: TermId,
    /// Number of joints/links for serial-arm terms (3 towers for delta terms).
    pub count: usize,
}

impl KinematicParameters {
    pub fn from_options(id: TermId, o: &Options) -> Result<Self, PhysicsError> {
        let count = match id {
            TermId::JointOffset => o.count("joints", 6, 12)?,
            TermId::LinkLength => o.count("links", 6, 12)?,
            _ => 3,
        };
        if count == 0 {
            return Err(o.bad(
                if id == TermId::JointOffset {
                    "joints"
                } else {
                    "links"
                },
                "must be at least 1",
            ));
        }
        Ok(Self { id, count })
    }
}

impl PhysicsTerm for KinematicParameters {
    fn id(&self) -> TermId {
        self.id
    }
    fn label(&self) -> String {
        self.id.as_str().to_string()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Kinematic
    }
    fn params(&self) -> Vec<ParamSpec> {
        let towers = ["a", "b", "c"];
        match self.id {
            TermId::DeltaRodLength => towers
                .iter()
                .map(|t| {
                    ParamSpec::new(
                        format!("rod_length_{t}"),
                        "m",
                        -5e-3,
                        5e-3,
                        0.0,
                        format!("diagonal rod length trim, tower {}", t.to_uppercase()),
                    )
                })
                .collect(),
            TermId::DeltaRadius => towers
                .iter()
                .map(|t| {
                    ParamSpec::new(
                        format!("radius_{t}"),
                        "m",
                        -5e-3,
                        5e-3,
                        0.0,
                        format!("delta radius trim, tower {}", t.to_uppercase()),
                    )
                })
                .collect(),
            TermId::DeltaTowerAngle => towers
                .iter()
                .map(|t| {
                    ParamSpec::new(
                        format!("angle_{t}"),
                        "rad",
                        -0.05,
                        0.05,
                        0.0,
                        format!("tower angle trim, tower {}", t.to_uppercase()),
                    )
                })
                .collect(),
            TermId::DeltaEndstop => towers
                .iter()
                .map(|t| {
                    ParamSpec::new(
                        format!("endstop_{t}"),
                        "m",
                        -5e-3,
                        5e-3,
                        0.0,
                        format!("endstop offset, tower {}", t.to_uppercase()),
                    )
                })
                .collect(),
            TermId::JointOffset => (1..=self.count)
                .map(|i| {
                    ParamSpec::new(
                        format!("q{i}"),
                        "rad",
                        -0.05,
                        0.05,
                        0.0,
                        format!("zero offset of joint {i}"),
                    )
                })
                .collect(),
            TermId::LinkLength => (1..=self.count)
                .map(|i| {
                    ParamSpec::new(
                        format!("l{i}"),
                        "m",
                        -5e-3,
                        5e-3,
                        0.0,
                        format!("length error of link {i}"),
                    )
                })
                .collect(),
            _ => vec![],
        }
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![]
    }
    fn predict(&self, _p: &[f64], _s: &Signals) -> Result<Prediction, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
    fn jacobian(&self, _p: &[f64], _s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
}

/// Displacement caused by a kinematic term and its Jacobian, given the forward kinematics as a
/// closure `forward(term_params) -> tool point (m)`: d = forward(p) − forward(0).
pub fn predict_through_kinematics(
    term: &dyn PhysicsTerm,
    p: &[f64],
    forward: &dyn Fn(&[f64]) -> Vector3<f64>,
) -> Result<(Vector3<f64>, DMatrix<f64>), PhysicsError> {
    let specs = term.params();
    if p.len() != specs.len() {
        return Err(PhysicsError::ParameterCount {
            term: term.label(),
            expected: specs.len(),
            got: p.len(),
        });
    }
    let zero = vec![0.0; p.len()];
    let d = forward(p) - forward(&zero);
    let typical: Vec<f64> = specs.iter().map(|s| s.typical_scale() * 1e-3).collect();
    let f = |q: &[f64]| Some(DVector::from_column_slice(forward(q).as_slice()));
    let j = central_difference(f, p, &relative_steps(p, 1e-4, &typical), Order::Second)
        .ok_or_else(|| PhysicsError::InvalidInput {
            what: format!("term `{}`", term.label()),
            reason: "central-difference Jacobian of the forward kinematics failed".into(),
        })?;
    Ok((d, j))
}
