//! `tracker_pose` — 6-dof pose of a laser tracker (or any instrument) in the frame tool points
//! are reported in (the workpiece frame; an arm's cell frame — the convention is stated once, in
//! crates/kinematics `instrument_pose`).
//!
//! X_LT = R_LTᵀ·(p − T_LT),  R_LT = Rx(α)·Ry(β)·Rz(δ)   (thesis P5 eqs 2, 21–22; Euler XYZ)
//!
//! p is the sighted tool point (signal `target_point`), T_LT = (tx, ty, tz) the tracker origin and
//! (α, β, δ) the Euler angles. R_LT is orthonormal, so R_LT⁻¹ = R_LTᵀ. Effect: the point in the
//! tracker frame, m.

use nalgebra::{DMatrix, DMatrixViewMut, DVector, Matrix3, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

// The rotation convention is kinematics' (the one Euler XYZ of the project), re-exported here
// for the callers that know it as the tracker pose's.
pub use metrocell_kinematics::transform::euler_xyz;
use metrocell_kinematics::transform::{drx, dry, drz, rx, ry, rz};

#[derive(Debug, Clone, Default)]
pub struct TrackerPose {
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
    /// The placement this pose is of (option `setup`): an instrument moved between groups of
    /// readings (a total station re-stationed, a tracker leap-frogged) has one pose per
    /// placement, each reading naming its own (signal `setup`). None: one pose for all.
    pub setup: Option<String>,
}

impl TrackerPose {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let setup = if o.has("setup") {
            let name = o.text("setup", None)?;
            if name.is_empty()
                || !name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
            {
                return Err(o.bad("setup", format!("`{name}` is not a setup name; use letters, digits, `_`, `-` or `.` (e.g. S1, station_3)")));
            }
            Some(name)
        } else {
            None
        };
        Ok(Self {
            instrument: super::instance(o)?,
            setup,
        })
    }
}

impl PhysicsTerm for TrackerPose {
    fn id(&self) -> TermId {
        TermId::TrackerPose
    }
    fn label(&self) -> String {
        // `tracker_pose`, `tracker_pose[lt1]`, `tracker_pose[S1]`, `tracker_pose[lt1@S1]`
        let instance = match (&self.instrument, &self.setup) {
            (Some(i), Some(s)) => Some(format!("{i}@{s}")),
            (i, s) => i.clone().or_else(|| s.clone()),
        };
        super::instance_label("tracker_pose", &instance)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn setup(&self) -> Option<&str> {
        self.setup.as_deref()
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
        Ok(Prediction {
            kind: self.effect(),
            value: DVector::from_column_slice(x.as_slice()),
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 6)?;
        let d = s.target(self)? - Vector3::new(p[0], p[1], p[2]);
        let (a, b, c) = (p[3], p[4], p[5]);
        let r = euler_xyz(a, b, c);
        let mut j = DMatrix::zeros(3, 6);
        j.view_mut((0, 0), (3, 3)).copy_from(&(-r.transpose()));
        let dr = [
            drx(a) * ry(b) * rz(c),
            rx(a) * dry(b) * rz(c),
            rx(a) * ry(b) * drz(c),
        ];
        for (k, m) in dr.iter().enumerate() {
            j.set_column(3 + k, &(m.transpose() * d));
        }
        Ok(j)
    }
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        check_len(self, p, 6)?;
        let point = match s.target_point {
            Some(v) => v,
            None => s.target(self)?,
        };
        PoseRotation::new(p[3], p[4], p[5]).evaluate_into(
            Vector3::new(p[0], p[1], p[2]),
            point,
            value,
            jac,
        );
        Ok(())
    }
}

/// R_LT and its derivatives by the three Euler angles: what every reading at one pose shares,
/// so that a caller evaluating many readings at one parameter vector (a fit) computes the
/// trigonometry once ([`Self::angles`] tells which pose it is for).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseRotation {
    angles: [f64; 3],
    r: Matrix3<f64>,
    /// ∂R_LT/∂α, ∂R_LT/∂β, ∂R_LT/∂δ.
    dr: [Matrix3<f64>; 3],
}

impl PoseRotation {
    pub fn new(alpha: f64, beta: f64, delta: f64) -> Self {
        let (a, b, c) = (alpha, beta, delta);
        Self {
            angles: [a, b, c],
            r: euler_xyz(a, b, c),
            dr: [
                drx(a) * ry(b) * rz(c),
                rx(a) * dry(b) * rz(c),
                rx(a) * ry(b) * drz(c),
            ],
        }
    }

    /// The Euler angles (α, β, δ) this rotation is of.
    pub fn angles(&self) -> [f64; 3] {
        self.angles
    }

    /// [`TrackerPose`]'s `evaluate_into` at this rotation (bit for bit): x = R_LTᵀ(point −
    /// origin) into `value[..3]`, ∂x/∂(tx, ty, tz, α, β, δ) into `jac` (3 × 6).
    pub fn evaluate_into(
        &self,
        origin: Vector3<f64>,
        point: Vector3<f64>,
        value: &mut [f64],
        mut jac: DMatrixViewMut<'_, f64>,
    ) {
        let d = point - origin;
        value[..3].copy_from_slice((self.r.transpose() * d).as_slice());
        jac.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(-self.r.transpose()));
        for (k, m) in self.dr.iter().enumerate() {
            jac.column_mut(3 + k).copy_from(&(m.transpose() * d));
        }
    }
}
