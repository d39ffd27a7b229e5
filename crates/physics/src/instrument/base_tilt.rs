//! `base_tilt` — the measured object's base tilted from level, as a levelled instrument sees it.
//!
//! P_level = Rx(roll)·Ry(pitch)·P
//!
//! P is the sighted tool point in the base frame (an arm's base, a machine's workpiece frame;
//! signal `target_point`), P_level the same point in a frame whose z is straight up (opposite
//! gravity) and whose x is the base's x turned by the tilt only. A levelled instrument (a total
//! station, a tracker with an electronic level) has its own z straight up to its compensator's σ:
//! each placement of it (each `tracker_pose[setup]`) is then a yaw and a translation from the
//! levelled frame, its residual tilt held by a prior of that σ — and what is left of the tilt
//! between the instrument's readings and the base is this term, one for every placement of the
//! recording (the base does not move between placements; the instrument does).
//!
//! Why a term: on tilted ground (a pallet, a seesaw, a ramp) the base is off level by mrad; with
//! one free 6-dof pose per placement that tilt is absorbed in each pose and the levelling tells
//! nothing; with levelled placements the tilt is two numbers shared by all of them, and each
//! placement's pose is four. Params: `roll` about x (first), `pitch` about y (second), rad;
//! Euler XYZ as `tracker_pose` (crates/kinematics `transform::euler_xyz`). Effect: the point in
//! the levelled frame, m (the forward model applies it before the instrument's pose).

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;
use metrocell_kinematics::transform::{drx, dry, rx, ry};

#[derive(Debug, Clone, Default)]
pub struct BaseTilt {
    /// Instance name (option `instrument`): the instrument whose levelling it is.
    pub instrument: Option<String>,
}

impl BaseTilt {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            instrument: super::instance(o)?,
        })
    }
}

/// Rx(roll)·Ry(pitch) and its derivatives by roll and pitch.
pub fn levelling(roll: f64, pitch: f64) -> (Matrix3<f64>, [Matrix3<f64>; 2]) {
    (
        rx(roll) * ry(pitch),
        [drx(roll) * ry(pitch), rx(roll) * dry(pitch)],
    )
}

impl PhysicsTerm for BaseTilt {
    fn id(&self) -> TermId {
        TermId::BaseTilt
    }
    fn label(&self) -> String {
        super::instance_label("base_tilt", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::PointInFrame(Frame::Tracker)
    }
    fn params(&self) -> Vec<ParamSpec> {
        let unusual = "a base tilted more than 20 mrad (1.1°) stands on a ramp or a loose support; one of more than 0.2 rad is no tilt but a wrong frame";
        vec![
            ParamSpec::new(
                "roll",
                "rad",
                -0.02,
                0.02,
                0.0,
                "tilt of the base about its x axis (first)",
            )
            .possible(-0.2, 0.2)
            .unusual_means(unusual),
            ParamSpec::new(
                "pitch",
                "rad",
                -0.02,
                0.02,
                0.0,
                "tilt of the base about its y axis (second)",
            )
            .possible(-0.2, 0.2)
            .unusual_means(unusual),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::TargetPoint]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 2)?;
        let x: Vector3<f64> = levelling(p[0], p[1]).0 * s.target(self)?;
        Ok(Prediction {
            kind: self.effect(),
            value: DVector::from_column_slice(x.as_slice()),
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 2)?;
        let t = s.target(self)?;
        let (_, d) = levelling(p[0], p[1]);
        let mut j = DMatrix::zeros(3, 2);
        for (k, m) in d.iter().enumerate() {
            j.set_column(k, &(m * t));
        }
        Ok(j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pitched_base_lowers_its_forward_points() {
        // pitch about y by +θ (right-handed): a point ahead on +x goes down by x·sin θ
        let t = BaseTilt::default();
        let s = Signals {
            target_point: Some(Vector3::new(2.0, 0.0, 0.0)),
            ..Signals::default()
        };
        let v = t.predict(&[0.0, 0.01], &s).unwrap().value;
        assert!((v[2] + 2.0 * 0.01f64.sin()).abs() < 1e-12, "{v}");
        // the Jacobian against central differences
        let p = [0.003, -0.007];
        let j = t
            .jacobian(
                &p,
                &Signals {
                    target_point: Some(Vector3::new(1.0, -0.5, 1.7)),
                    ..Signals::default()
                },
            )
            .unwrap();
        for k in 0..2 {
            let h = 1e-7;
            let (mut a, mut b) = (p, p);
            a[k] += h;
            b[k] -= h;
            let s = Signals {
                target_point: Some(Vector3::new(1.0, -0.5, 1.7)),
                ..Signals::default()
            };
            let fd =
                (t.predict(&a, &s).unwrap().value - t.predict(&b, &s).unwrap().value) / (2.0 * h);
            assert!((fd - j.column(k)).norm() < 1e-8, "column {k}");
        }
    }
}
