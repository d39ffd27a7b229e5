//! Serial arms: a chain of joints, each `pre · motion(q) · post`, with forward kinematics of every link,
//! the geometric Jacobian; inverse kinematics on the shared solver is in [`crate::serial_ik`].
//!
//! Frame of a joint: `pre` carries the parent link frame to the joint frame, in which the unit `axis` is
//! expressed (URDF: `pre` = `<origin>`, `post` = identity; DH: see [`crate::dh`]). A revolute joint rotates
//! by `q + offset` about `axis`, a prismatic one translates by `q + offset` along it, a fixed joint takes no
//! variable. The geometric Jacobian is 6×n: rows 0–2 the linear velocity of the tool point in the base frame,
//! rows 3–5 the angular velocity in the base frame.

use crate::error::{check_finite, KinematicsError};
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

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
}

impl Joint {
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

    /// Number of joint variables (non-fixed joints).
    pub fn dof(&self) -> usize {
        self.joints
            .iter()
            .filter(|j| j.kind != JointKind::Fixed)
            .count()
    }

    /// Names of the movable joints, in variable order.
    pub fn variable_names(&self) -> Vec<String> {
        self.joints
            .iter()
            .filter(|j| j.kind != JointKind::Fixed)
            .map(|j| j.name.clone())
            .collect()
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
        let mut t = self.base;
        let mut links = Vec::with_capacity(self.joints.len());
        let mut k = 0;
        for j in &self.joints {
            let v = if j.kind == JointKind::Fixed {
                0.0
            } else {
                k += 1;
                q[k - 1]
            };
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
        let mut t = self.base;
        let mut k = 0;
        for j in &self.joints {
            let joint_frame = t * j.pre;
            let z = joint_frame.rotation * j.axis.into_inner();
            let o = joint_frame.translation.vector;
            let v = match j.kind {
                JointKind::Fixed => 0.0,
                _ => q[k],
            };
            match j.kind {
                JointKind::Revolute => {
                    jac.fixed_view_mut::<3, 1>(0, k)
                        .copy_from(&z.cross(&(p - o)));
                    jac.fixed_view_mut::<3, 1>(3, k).copy_from(&z);
                    k += 1;
                }
                JointKind::Prismatic => {
                    jac.fixed_view_mut::<3, 1>(0, k).copy_from(&z);
                    k += 1;
                }
                JointKind::Fixed => {}
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
        let mut t = self.base;
        let mut k = 0;
        for (i, j) in self.joints.iter().enumerate() {
            for a in 0..3 {
                jac.fixed_view_mut::<3, 1>(0, 3 * i + a)
                    .copy_from(&(t.rotation * Vector3::ith(a, 1.0)));
            }
            let v = if j.kind == JointKind::Fixed {
                0.0
            } else {
                k += 1;
                q[k - 1]
            };
            t *= j.transform(v);
        }
        Ok(jac)
    }
}
