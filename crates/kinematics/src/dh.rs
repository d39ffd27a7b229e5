//! Denavit–Hartenberg tables (standard and modified) → serial chains, and the Jacobian of the tool pose
//! w.r.t. the DH parameters (the `joint_offset` and `link_length` physics terms).
//!
//! Standard (distal) DH link transform: `A_i = Rz(θ_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)`.
//! Modified (proximal, Craig) DH: `A_i = Rx(α_{i−1}) · Tx(a_{i−1}) · Rz(θ_i) · Tz(d_i)`; in a modified row the
//! `a` and `alpha` fields hold `a_{i−1}`, `α_{i−1}`.
//! A revolute row adds its joint variable to θ, a prismatic row to d; a fixed row has no variable.

use crate::error::{check_finite, KinematicsError};
use crate::serial::{Joint, JointKind, SerialChain};
use crate::transform::{rot_x, rot_z, trans};
use nalgebra::{DMatrix, Isometry3, Vector3};

/// Which DH convention a table uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DhConvention {
    Standard,
    Modified,
}

/// One row of a DH table (metres, radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhRow {
    pub theta: f64,
    pub d: f64,
    pub a: f64,
    pub alpha: f64,
    pub kind: JointKind,
}

impl DhRow {
    pub fn revolute(theta: f64, d: f64, a: f64, alpha: f64) -> Self {
        Self {
            theta,
            d,
            a,
            alpha,
            kind: JointKind::Revolute,
        }
    }
    pub fn prismatic(theta: f64, d: f64, a: f64, alpha: f64) -> Self {
        Self {
            theta,
            d,
            a,
            alpha,
            kind: JointKind::Prismatic,
        }
    }
    pub fn fixed(theta: f64, d: f64, a: f64, alpha: f64) -> Self {
        Self {
            theta,
            d,
            a,
            alpha,
            kind: JointKind::Fixed,
        }
    }

    /// Link transform with the row's values taken as they stand (joint variable already folded in).
    pub fn transform(&self, convention: DhConvention) -> Isometry3<f64> {
        match convention {
            DhConvention::Standard => {
                rot_z(self.theta)
                    * trans(0.0, 0.0, self.d)
                    * trans(self.a, 0.0, 0.0)
                    * rot_x(self.alpha)
            }
            DhConvention::Modified => {
                rot_x(self.alpha)
                    * trans(self.a, 0.0, 0.0)
                    * rot_z(self.theta)
                    * trans(0.0, 0.0, self.d)
            }
        }
    }
}

/// Names of the four parameters of each row, in the column order of [`DhTable::parameter_jacobian`].
pub const DH_PARAMETER_NAMES: [&str; 4] = ["theta", "d", "a", "alpha"];

/// A DH table with its convention.
#[derive(Debug, Clone, PartialEq)]
pub struct DhTable {
    pub convention: DhConvention,
    pub rows: Vec<DhRow>,
}

impl DhTable {
    /// Validates that every entry is finite.
    pub fn new(convention: DhConvention, rows: Vec<DhRow>) -> Result<Self, KinematicsError> {
        for (i, r) in rows.iter().enumerate() {
            for (name, v) in DH_PARAMETER_NAMES.iter().zip([r.theta, r.d, r.a, r.alpha]) {
                check_finite(&format!("DH row {i} {name}"), v)?;
            }
        }
        Ok(Self { convention, rows })
    }

    /// The equivalent serial chain (joint names `joint_1`, `joint_2`, ...).
    pub fn to_chain(&self) -> SerialChain {
        let joints = self
            .rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let (pre, post) = match self.convention {
                    DhConvention::Standard => (
                        Isometry3::identity(),
                        rot_z(r.theta)
                            * trans(0.0, 0.0, r.d)
                            * trans(r.a, 0.0, 0.0)
                            * rot_x(r.alpha),
                    ),
                    DhConvention::Modified => (
                        rot_x(r.alpha) * trans(r.a, 0.0, 0.0),
                        rot_z(r.theta) * trans(0.0, 0.0, r.d),
                    ),
                };
                Joint::new(
                    format!("joint_{}", i + 1),
                    r.kind,
                    pre,
                    Vector3::z_axis(),
                    post,
                )
            })
            .collect();
        SerialChain::new(joints)
    }

    /// Cumulative frames `T_0^i` (i = 1..n) for joint values `q` (one per non-fixed row).
    pub fn frames(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, KinematicsError> {
        Ok(self.to_chain().forward(q)?.links)
    }

    /// Jacobian (6 × 4n) of the last frame's origin (rows 0–2) and orientation (rows 3–5, angular
    /// velocity) w.r.t. the DH parameters; columns per row in [`DH_PARAMETER_NAMES`] order. Analytic:
    /// a rotation parameter about unit axis `u` through point `o` moves the tip by `u × (p − o)`,
    /// a translation parameter along `u` moves it by `u`.
    pub fn parameter_jacobian(&self, q: &[f64]) -> Result<DMatrix<f64>, KinematicsError> {
        let frames = self.frames(q)?;
        let n = self.rows.len();
        let p = frames[n - 1].translation.vector;
        let mut jac = DMatrix::zeros(6, 4 * n);
        let mut put = |col: usize, lin: Vector3<f64>, ang: Vector3<f64>| {
            jac.fixed_view_mut::<3, 1>(0, col).copy_from(&lin);
            jac.fixed_view_mut::<3, 1>(3, col).copy_from(&ang);
        };
        for i in 0..n {
            let prev = if i == 0 {
                Isometry3::identity()
            } else {
                frames[i - 1]
            };
            let cur = frames[i];
            let axis = |t: &Isometry3<f64>, k: usize| t.rotation * Vector3::ith(k, 1.0);
            let origin = |t: &Isometry3<f64>| t.translation.vector;
            match self.convention {
                DhConvention::Standard => {
                    let z = axis(&prev, 2);
                    let o = origin(&prev);
                    let x = axis(&cur, 0);
                    let oc = origin(&cur);
                    put(4 * i, z.cross(&(p - o)), z);
                    put(4 * i + 1, z, Vector3::zeros());
                    put(4 * i + 2, x, Vector3::zeros());
                    put(4 * i + 3, x.cross(&(p - oc)), x);
                }
                DhConvention::Modified => {
                    let x = axis(&prev, 0);
                    let o = origin(&prev);
                    let z = axis(&cur, 2);
                    let oc = origin(&cur);
                    put(4 * i, z.cross(&(p - oc)), z);
                    put(4 * i + 1, z, Vector3::zeros());
                    put(4 * i + 2, x, Vector3::zeros());
                    put(4 * i + 3, x.cross(&(p - o)), x);
                }
            }
        }
        Ok(jac)
    }
}
