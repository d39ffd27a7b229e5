//! Serial arms: a chain of joints, each `pre · motion(q) · post`, with forward kinematics of every link,
//! the geometric Jacobian; inverse kinematics on the shared solver is in [`crate::serial_ik`].
//!
//! Frame of a joint: `pre` carries the parent link frame to the joint frame, in which the unit `axis` is
//! expressed (URDF: `pre` = `<origin>`, `post` = identity; DH: see [`crate::dh`]). A revolute joint rotates
//! by `q + offset` about `axis`, a prismatic one translates by `q + offset` along it, a fixed joint takes no
//! variable. A *mimic* joint (URDF `<mimic>`: a telescoping column's second segment driven with the first)
//! takes no variable of its own either: its value is `multiplier·q_master + offset`, so the chain's
//! variables (`dof`, `variable_names`) are the independent joints only, and the Jacobian's column of a
//! master holds its mimics' motion too. The geometric Jacobian is 6×n: rows 0–2 the linear velocity of the tool point in the base frame,
//! rows 3–5 the angular velocity in the base frame.

use crate::error::{check_finite, KinematicsError};
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

/// A joint's frame before its motion and after it (see [`SerialChain::joint_frames`]).
pub type JointFrames = (Isometry3<f64>, Isometry3<f64>);

/// What a joint does with its variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis (rad).
    Revolute,
    /// Translation along the axis (m).
    Prismatic,
    /// No variable.
    Fixed,
}

/// One joint of a serial chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    /// Parent link frame → joint frame.
    pub pre: Isometry3<f64>,
    /// Unit joint axis in the joint frame.
    pub axis: Unit<Vector3<f64>>,
    /// Joint frame (after motion) → child link frame.
    pub post: Isometry3<f64>,
    /// Constant added to the joint variable (the `joint_offset` physics term) (rad or m).
    pub offset: f64,
    /// Set when the joint follows another one of the chain (URDF `<mimic>`).
    pub mimic: Option<Mimic>,
    /// `[lower, upper]` of its value (rad or m), when the description gives them.
    pub limits: Option<[f64; 2]>,
    /// Mass and centre of mass of its child link (URDF `<inertial>`), when given.
    pub inertial: Option<LinkInertial>,
}

/// A joint whose value follows another's: `multiplier·q_master + offset` (URDF `<mimic>`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mimic {
    /// Index of the master joint in the chain's `joints`.
    pub master: usize,
    pub multiplier: f64,
    pub offset: f64,
}

/// A link's mass (kg) and the position of its centre of mass in its own frame (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkInertial {
    pub mass: f64,
    pub centre_of_mass: Vector3<f64>,
}

impl Joint {
    /// A joint with no offset, mimic, limits or inertial.
    pub fn new(
        name: impl Into<String>,
        kind: JointKind,
        pre: Isometry3<f64>,
        axis: Unit<Vector3<f64>>,
        post: Isometry3<f64>,
    ) -> Self {
        Self {
            name: name.into(),
            kind,
            pre,
            axis,
            post,
            offset: 0.0,
            mimic: None,
            limits: None,
            inertial: None,
        }
    }

    /// Whether the joint has a variable of its own (movable, not a mimic).
    pub fn is_variable(&self) -> bool {
        self.kind != JointKind::Fixed && self.mimic.is_none()
    }

    /// Transform parent link → child link for joint value `q` (ignored for fixed joints).
    pub fn transform(&self, q: f64) -> Isometry3<f64> {
        self.pre * self.motion(q) * self.post
    }

    fn motion(&self, q: f64) -> Isometry3<f64> {
        let v = q + self.offset;
        match self.kind {
            JointKind::Revolute => Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_axis_angle(&self.axis, v),
            ),
            JointKind::Prismatic => Isometry3::from_parts(
                Translation3::from(self.axis.into_inner() * v),
                UnitQuaternion::identity(),
            ),
            JointKind::Fixed => Isometry3::identity(),
        }
    }
}

/// A serial chain: base frame, joints from base to tip, and a tool transform after the last link.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialChain {
    pub base: Isometry3<f64>,
    pub joints: Vec<Joint>,
    pub tool: Isometry3<f64>,
}

/// Forward kinematics of every link.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainPose {
    /// Base → child link of joint i, one per joint (fixed joints included).
    pub links: Vec<Isometry3<f64>>,
    /// Base → tool frame.
    pub tool: Isometry3<f64>,
}

/// Target of an inverse-kinematics request, in the base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IkTarget {
    /// Tool-point position only (m).
    Position(Vector3<f64>),
    /// Full tool pose.
    Pose(Isometry3<f64>),
}

/// Settings of the inverse kinematics ([`crate::serial_ik`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkSettings {
    pub max_iterations: usize,
    /// Converged when the position error is below this (m) ...
    pub position_tolerance: f64,
    /// ... and the orientation error below this (rad) (ignored for position-only targets).
    pub orientation_tolerance: f64,
    /// Initial Levenberg–Marquardt damping λ₀ (relative to the column-scaled normal matrix).
    pub initial_damping: f64,
    /// Weight of 1 rad of orientation error relative to 1 m of position error.
    pub orientation_weight: f64,
}

impl Default for IkSettings {
    fn default() -> Self {
        Self {
            max_iterations: 500,
            position_tolerance: 1e-12,
            orientation_tolerance: 1e-12,
            initial_damping: 1e-2,
            orientation_weight: 1.0,
        }
    }
}

/// Outcome of inverse kinematics: the joint values and how well they meet the target.
#[derive(Debug, Clone, PartialEq)]
pub struct IkReport {
    pub q: DVector<f64>,
    pub converged: bool,
    pub iterations: usize,
    /// Final position error norm (m).
    pub position_error: f64,
    /// Final orientation error angle (rad) (0 for position-only targets).
    pub orientation_error: f64,
    /// Final damping λ.
    pub damping: f64,
}

impl SerialChain {
    /// Chain with identity base and tool.
    pub fn new(joints: Vec<Joint>) -> Self {
        Self {
            base: Isometry3::identity(),
            joints,
            tool: Isometry3::identity(),
        }
    }

    /// Number of joint variables (movable joints that are not mimics).
    pub fn dof(&self) -> usize {
        self.joints.iter().filter(|j| j.is_variable()).count()
    }

    /// Names of the joint variables (movable joints that are not mimics), in variable order.
    pub fn variable_names(&self) -> Vec<String> {
        self.joints
            .iter()
            .filter(|j| j.is_variable())
            .map(|j| j.name.clone())
            .collect()
    }

    /// The variable index of each joint (None for fixed joints and mimics).
    pub fn variable_indices(&self) -> Vec<Option<usize>> {
        let mut k = 0;
        self.joints
            .iter()
            .map(|j| {
                j.is_variable().then(|| {
                    k += 1;
                    k - 1
                })
            })
            .collect()
    }

    /// Each joint's variable and the factor its motion takes of it: `Some((k, 1))` for a joint
    /// with its own variable k, `Some((k, multiplier))` for a mimic of variable k's joint, None
    /// for a fixed joint.
    pub fn drives(&self) -> Vec<Option<(usize, f64)>> {
        let vars = self.variable_indices();
        self.joints
            .iter()
            .enumerate()
            .map(|(i, j)| match (vars[i], j.mimic) {
                (Some(k), _) => Some((k, 1.0)),
                (None, Some(m)) if j.kind != JointKind::Fixed => vars
                    .get(m.master)
                    .copied()
                    .flatten()
                    .map(|k| (k, m.multiplier)),
                _ => None,
            })
            .collect()
    }

    /// Each joint's value for the variables `q` (0 for fixed joints, `multiplier·q_master +
    /// offset` for mimics), and [`Self::drives`] (for the Jacobian).
    fn joint_values(&self, q: &[f64]) -> (Vec<f64>, Vec<Option<(usize, f64)>>) {
        let driven = self.drives();
        let values = self
            .joints
            .iter()
            .zip(&driven)
            .map(|(j, d)| match (d, j.mimic) {
                (Some((k, _)), Some(m)) => m.multiplier * q[*k] + m.offset,
                (Some((k, _)), None) => q[*k],
                (None, _) => 0.0,
            })
            .collect();
        (values, driven)
    }

    /// The frame of every joint before its motion (parent link × `pre`: its axis and origin in the
    /// base frame) and after it (the child link), at `q`.
    pub fn joint_frames(&self, q: &[f64]) -> Result<Vec<JointFrames>, KinematicsError> {
        self.check_q(q)?;
        let (values, _) = self.joint_values(q);
        let mut t = self.base;
        let mut out = Vec::with_capacity(self.joints.len());
        for (j, v) in self.joints.iter().zip(values) {
            let before = t * j.pre;
            t *= j.transform(v);
            out.push((before, t));
        }
        Ok(out)
    }

    pub(crate) fn check_q(&self, q: &[f64]) -> Result<(), KinematicsError> {
        if q.len() != self.dof() {
            return Err(KinematicsError::LengthMismatch {
                field: "joint values q".into(),
                got: q.len(),
                expected: self.dof(),
            });
        }
        for (i, v) in q.iter().enumerate() {
            check_finite(&format!("q[{i}]"), *v)?;
        }
        Ok(())
    }

    /// Forward kinematics of all links and the tool.
    pub fn forward(&self, q: &[f64]) -> Result<ChainPose, KinematicsError> {
        self.check_q(q)?;
        let (values, _) = self.joint_values(q);
        let mut t = self.base;
        let mut links = Vec::with_capacity(self.joints.len());
        for (j, v) in self.joints.iter().zip(values) {
            t *= j.transform(v);
            links.push(t);
        }
        Ok(ChainPose {
            links,
            tool: t * self.tool,
        })
    }

    /// Base → tool frame.
    pub fn tool_pose(&self, q: &[f64]) -> Result<Isometry3<f64>, KinematicsError> {
        Ok(self.forward(q)?.tool)
    }

    /// Geometric Jacobian (6 × dof) of the tool frame, base-frame components.
    pub fn jacobian(&self, q: &[f64]) -> Result<DMatrix<f64>, KinematicsError> {
        self.check_q(q)?;
        let tool = self.tool_pose(q)?;
        let p = tool.translation.vector;
        let mut jac = DMatrix::zeros(6, self.dof());
        let (values, driven) = self.joint_values(q);
        let mut t = self.base;
        for ((j, v), d) in self.joints.iter().zip(values).zip(driven) {
            let joint_frame = t * j.pre;
            let z = joint_frame.rotation * j.axis.into_inner();
            let o = joint_frame.translation.vector;
            // a mimic's motion goes to its master's column, times its multiplier
            if let Some((k, factor)) = d {
                match j.kind {
                    JointKind::Revolute => {
                        let lin = jac.fixed_view::<3, 1>(0, k) + z.cross(&(p - o)) * factor;
                        let ang = jac.fixed_view::<3, 1>(3, k) + z * factor;
                        jac.fixed_view_mut::<3, 1>(0, k).copy_from(&lin);
                        jac.fixed_view_mut::<3, 1>(3, k).copy_from(&ang);
                    }
                    JointKind::Prismatic => {
                        let lin = jac.fixed_view::<3, 1>(0, k) + z * factor;
                        jac.fixed_view_mut::<3, 1>(0, k).copy_from(&lin);
                    }
                    JointKind::Fixed => {}
                }
            }
            t *= j.transform(v);
        }
        Ok(jac)
    }

    /// Jacobian (6 × dof) of the tool frame w.r.t. the joint offsets (`joint_offset` term). An offset adds to its
    /// joint variable, so this equals the geometric Jacobian; named separately so callers say what they mean.
    pub fn joint_offset_jacobian(&self, q: &[f64]) -> Result<DMatrix<f64>, KinematicsError> {
        self.jacobian(q)
    }

    /// Jacobian (6 × 3·joints) of the tool frame w.r.t. the translation part of every joint's `pre` transform
    /// (URDF `<origin xyz>`, the `link_length` term), columns `[x, y, z]` per joint (fixed joints included),
    /// expressed in the parent link frame. A translation moves the tool point by the parent frame's axis and
    /// leaves the orientation unchanged, so rows 3–5 are zero.
    pub fn origin_translation_jacobian(&self, q: &[f64]) -> Result<DMatrix<f64>, KinematicsError> {
        self.check_q(q)?;
        let mut jac = DMatrix::zeros(6, 3 * self.joints.len());
        let (values, _) = self.joint_values(q);
        let mut t = self.base;
        for (i, (j, v)) in self.joints.iter().zip(values).enumerate() {
            for a in 0..3 {
                jac.fixed_view_mut::<3, 1>(0, 3 * i + a)
                    .copy_from(&(t.rotation * Vector3::ith(a, 1.0)));
            }
            t *= j.transform(v);
        }
        Ok(jac)
    }
}
