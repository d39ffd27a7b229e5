//! `tracker_pose` — 6-dof pose of a laser tracker (or any instrument) in the frame tool points
//! are reported in (the workpiece frame; an arm's cell frame — the convention is stated once, in
//! crates/kinematics `instrument_pose`).
//!
//! X_LT = R_LTᵀ·(p − T_LT),  R_LT = Rx(α)·Ry(β)·Rz(δ)   (thesis P5 eqs 2, 21–22; Euler XYZ)
//!
//! p is the sighted tool point (signal `target_point`), T_LT = (tx, ty, tz) the tracker origin and
//! (α, β, δ) the Euler angles. R_LT is orthonormal, so R_LT⁻¹ = R_LTᵀ. Effect: the point in the
//! tracker frame, m.

use nalgebra::{DMatrix, DMatrixViewMut, DVector, Vector3};

use crate::term_id::TermId;
use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};

// The rotation convention is kinematics' (the one Euler XYZ of the project), re-exported here
// for the callers that know it as the tracker pose's.
pub use metrocell_kinematics::transform::euler_xyz;
use metrocell_kinematics::transform::{drx, dry, drz, rx, ry, rz};

#[derive(Debug, Clone, Default)]
pub struct TrackerPose {
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl TrackerPose {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self { instrument: super::instance(o)? })
    }
}

impl PhysicsTerm for TrackerPose {
    fn id(&self) -> TermId {
        TermId::TrackerPose
    }
    fn label(&self) -> String {
        super::instance_label("tracker_pose", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::PointInFrame(Frame::Tracker)
    }
    fn params(&self) -> Vec<ParamSpec> {
        let pi = std::f64::consts::PI;
        vec![
            ParamSpec::new("tx", "m", -30.0, 30.0, 0.0, "tracker origin x"),
            ParamSpec::new("ty", "m", -30.0, 30.0, 0.0, "tracker origin y"),
            ParamSpec::new("tz", "m", -30.0, 30.0, 0.0, "tracker origin z"),
            ParamSpec::new("alpha", "rad", -pi, pi, 0.0, "Euler angle about X (first)"),
            ParamSpec::new("beta", "rad", -pi, pi, 0.0, "Euler angle about Y (second)"),
            ParamSpec::new("delta", "rad", -pi, pi, 0.0, "Euler angle about Z (third)"),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::TargetPoint]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 6)?;
        let d = s.target(self)? - Vector3::new(p[0], p[1], p[2]);
        let x = euler_xyz(p[3], p[4], p[5]).transpose() * d;
        Ok(Prediction { kind: self.effect(), value: DVector::from_column_slice(x.as_slice()) })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 6)?;
        let d = s.target(self)? - Vector3::new(p[0], p[1], p[2]);
        let (a, b, c) = (p[3], p[4], p[5]);
        let r = euler_xyz(a, b, c);
        let mut j = DMatrix::zeros(3, 6);
        j.view_mut((0, 0), (3, 3)).copy_from(&(-r.transpose()));
        let dr = [drx(a) * ry(b) * rz(c), rx(a) * dry(b) * rz(c), rx(a) * ry(b) * drz(c)];
        for (k, m) in dr.iter().enumerate() {
            j.set_column(3 + k, &(m.transpose() * d));
        }
        Ok(j)
    }
    fn evaluate_into(&self, p: &[f64], s: &Signals, value: &mut [f64], mut jac: DMatrixViewMut<'_, f64>) -> Result<(), PhysicsError> {
        check_len(self, p, 6)?;
        let point = match s.target_point {
            Some(v) => v,
            None => s.target(self)?,
        };
        let d = point - Vector3::new(p[0], p[1], p[2]);
        let (a, b, c) = (p[3], p[4], p[5]);
        let r = euler_xyz(a, b, c);
        value[..3].copy_from_slice((r.transpose() * d).as_slice());
        jac.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-r.transpose()));
        let dr = [drx(a) * ry(b) * rz(c), rx(a) * dry(b) * rz(c), rx(a) * ry(b) * drz(c)];
        for (k, m) in dr.iter().enumerate() {
            jac.column_mut(3 + k).copy_from(&(m.transpose() * d));
        }
        Ok(())
    }
}
