//! `frame_misalignment` — small rigid misalignment between two frames, e.g. an artefact plate
//! rotated by θ about Z on the table (thesis P4 eq. 6) or a fixture offset.
//!
//! d = ω × (p − o) + t,   ω = (rx, ry, rz) small rotation (rad), t = (tx, ty, tz) (m),
//! o = option `origin` (m, default 0), p = signal `workpiece_point` (nominal feature position,
//! workpiece frame).
//! First order in ω (small-angle): valid while |ω|·|p − o| is far below the tolerance of interest;
//! large rotations are a `tracker_pose`-style full transform. Frame: workpiece.

use nalgebra::{DMatrix, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct FrameMisalignment {
    pub origin: Vector3<f64>,
}

impl FrameMisalignment {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            origin: o.vector3("origin", "m", Some(Vector3::zeros()))?,
        })
    }
}

impl PhysicsTerm for FrameMisalignment {
    fn id(&self) -> TermId {
        TermId::FrameMisalignment
    }
    fn label(&self) -> String {
        "frame_misalignment".into()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Workpiece)
    }
    fn params(&self) -> Vec<ParamSpec> {
        let mut v: Vec<ParamSpec> = ["rx", "ry", "rz"]
            .iter()
            .map(|n| {
                ParamSpec::new(
                    *n,
                    "rad",
                    -0.05,
                    0.05,
                    0.0,
                    format!("small rotation about {}", &n[1..]),
                )
            })
            .collect();
        v.extend(["tx", "ty", "tz"].iter().map(|n| {
            ParamSpec::new(
                *n,
                "m",
                -0.1,
                0.1,
                0.0,
                format!("translation along {}", &n[1..]),
            )
        }));
        v
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::WorkpiecePoint]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 6)?;
        let r = s.workpiece(self)? - self.origin;
        let w = Vector3::new(p[0], p[1], p[2]);
        Ok(displacement(
            Frame::Workpiece,
            w.cross(&r) + Vector3::new(p[3], p[4], p[5]),
        ))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 6)?;
        let r = s.workpiece(self)? - self.origin;
        let mut j = DMatrix::zeros(3, 6);
        // ∂(ω × r)/∂ω = −[r]×
        let neg_skew = -r.cross_matrix();
        j.view_mut((0, 0), (3, 3)).copy_from(&neg_skew);
        j.view_mut((0, 3), (3, 3)).fill_with_identity();
        Ok(j)
    }
}
