//! Five-axis machine with a tilting B / rotary C table (seed 004, Universidad Politécnica de Pachuca prototype).
//!
//! Linear axes: the paper's DH table with its `a`/`α` column headers swapped back (seed 004 digest §2.1),
//! standard DH `A = Rz(θ)·Tz(d)·Tx(a)·Rx(α)`:
//!
//! | i | θ    | d   | a   | α    |
//! |---|------|-----|-----|------|
//! | 1 | 90°  | d0  | 0   | 0°   |
//! | 2 | 0°   | 0   | d1  | 90°  |
//! | 3 | −90° | d2  | 0   | −90° |
//! | 4 | 0°   | 0   | d3  | 0°   |
//!
//! giving the spindle gauge point `(x, y, z) = (d2, d1, d0 − d3)` in the machine frame (paper eq. 1):
//! d1 = Y travel, d2 = X travel, d3 = Z travel (downwards), d0 = constant base height. The tool points along
//! frame 4's x axis, which is the machine's −z: the tool tip is the gauge point plus `tool_length` along −z.
//!
//! Rotary axes (not in the paper's kinematics; digest §6.1 item 2): B tilts the cradle about the machine y axis,
//! C turns the table about the cradle's z axis (C rides on B), so the workpiece frame is
//! `T_machine_workpiece = Trans(b_pivot) · Ry(B) · Trans(c_offset) · Rz(C) · Trans(workpiece_offset)`.
//! Positive B and C follow the right-hand rule about +y and +z. The tool axis `k` is the unit vector from the
//! tip towards the spindle (machine +z), reported in the workpiece frame.

use crate::dh::{DhConvention, DhRow, DhTable};
use crate::error::{check_finite, KinematicsError};
use crate::transform::{rot_y, rot_z};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use std::f64::consts::{FRAC_PI_2, PI};

/// Geometry of the five-axis table/table machine (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiveAxisGeometry {
    /// DH constant d0: base height of the linear-axis chain.
    pub d0: f64,
    /// Tool length from the gauge point to the tip, along −z.
    pub tool_length: f64,
    /// A point on the B axis (machine frame).
    pub b_pivot: Vector3<f64>,
    /// From the B pivot to a point on the C axis, in the cradle frame (B = 0).
    pub c_offset: Vector3<f64>,
    /// From the C-axis point to the workpiece origin, in the table frame (C = 0).
    pub workpiece_offset: Vector3<f64>,
    /// Allowed B range (rad) (the paper: up to 180° of travel).
    pub b_limits: (f64, f64),
}

/// Axis values: linear DH variables and rotary angles (metres, radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiveAxisJoints {
    /// Y travel (DH d1).
    pub d1: f64,
    /// X travel (DH d2).
    pub d2: f64,
    /// Z travel, downwards (DH d3).
    pub d3: f64,
    pub b: f64,
    pub c: f64,
}

/// Tool tip position and tool axis in the workpiece frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolPose {
    pub tip: Vector3<f64>,
    /// Unit vector from the tip towards the spindle.
    pub axis: Vector3<f64>,
}

/// One inverse-kinematics solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiveAxisSolution {
    pub joints: FiveAxisJoints,
    /// True at B = 0 (tool along the C axis): C is then free and taken from the caller's hint.
    pub singular: bool,
}

impl FiveAxisGeometry {
    /// Geometry with every offset zero and B limited to ±90° (180° of travel).
    pub fn new(d0: f64, tool_length: f64) -> Self {
        Self {
            d0,
            tool_length,
            b_pivot: Vector3::zeros(),
            c_offset: Vector3::zeros(),
            workpiece_offset: Vector3::zeros(),
            b_limits: (-FRAC_PI_2, FRAC_PI_2),
        }
    }

    /// The reconstructed DH table of the linear axes for DH variables (d1, d2, d3).
    pub fn linear_dh(&self, d1: f64, d2: f64, d3: f64) -> DhTable {
        let deg = PI / 180.0;
        DhTable {
            convention: DhConvention::Standard,
            rows: vec![
                DhRow::fixed(90.0 * deg, self.d0, 0.0, 0.0),
                DhRow::fixed(0.0, 0.0, d1, 90.0 * deg),
                DhRow::fixed(-90.0 * deg, d2, 0.0, -90.0 * deg),
                DhRow::fixed(0.0, 0.0, d3, 0.0),
            ],
        }
    }

    /// Cumulative frames `T_0^1 … T_0^4` of the linear axes (paper's printed matrices, corrected).
    pub fn linear_frames(&self, d1: f64, d2: f64, d3: f64) -> Vec<Isometry3<f64>> {
        let table = self.linear_dh(d1, d2, d3);
        let mut t = Isometry3::identity();
        table
            .rows
            .iter()
            .map(|r| {
                t *= r.transform(table.convention);
                t
            })
            .collect()
    }

    /// Machine frame ← workpiece frame for rotary angles B, C.
    pub fn machine_from_workpiece(&self, b: f64, c: f64) -> Isometry3<f64> {
        Isometry3::from(Translation3::from(self.b_pivot))
            * rot_y(b)
            * Isometry3::from(Translation3::from(self.c_offset))
            * rot_z(c)
            * Isometry3::from(Translation3::from(self.workpiece_offset))
    }

    /// Forward kinematics: tool tip and tool axis in the workpiece frame.
    pub fn forward(&self, j: &FiveAxisJoints) -> Result<ToolPose, KinematicsError> {
        for (name, v) in [
            ("d1", j.d1),
            ("d2", j.d2),
            ("d3", j.d3),
            ("B", j.b),
            ("C", j.c),
        ] {
            check_finite(name, v)?;
        }
        let t04 = *self
            .linear_frames(j.d1, j.d2, j.d3)
            .last()
            .expect("four rows");
        let tool_dir = t04.rotation * Vector3::x(); // = machine −z
        let tip_machine = t04.translation.vector + tool_dir * self.tool_length;
        let w = self.machine_from_workpiece(j.b, j.c).inverse();
        Ok(ToolPose {
            tip: (w * Point3::from(tip_machine)).coords,
            axis: w.rotation * (-tool_dir),
        })
    }

    /// Inverse kinematics: all axis settings (up to two branches, B of either sign) that put the tool tip at
    /// `pose.tip` with tool axis `pose.axis` (workpiece frame). At B = 0 the C angle is free: `c_hint` is used.
    /// Branches outside `b_limits` are dropped; C is wrapped to (−π, π].
    pub fn inverse(
        &self,
        pose: &ToolPose,
        c_hint: f64,
    ) -> Result<Vec<FiveAxisSolution>, KinematicsError> {
        for (i, v) in pose.tip.iter().chain(pose.axis.iter()).enumerate() {
            check_finite(
                ["tip.x", "tip.y", "tip.z", "axis.x", "axis.y", "axis.z"][i],
                *v,
            )?;
        }
        let n = pose.axis.norm();
        if n < 1e-12 {
            return Err(KinematicsError::InvalidValue {
                field: "tool axis".into(),
                value: n,
                reason: "zero vector".into(),
            });
        }
        let k = pose.axis / n;
        // k_workpiece = Rz(−C)·Ry(−B)·ẑ = (−sinB·cosC, sinB·sinC, cosB)
        let mut angles = Vec::new();
        let sin_b = (k.x * k.x + k.y * k.y).sqrt();
        if sin_b < 1e-12 {
            // Tool along the C axis: B = 0 (upright) or B = π (table upside down); C is free.
            angles.push((if k.z > 0.0 { 0.0 } else { PI }, c_hint, true));
        } else {
            let b = sin_b.atan2(k.z);
            let c = k.y.atan2(-k.x);
            angles.push((b, c, false));
            angles.push((-b, c + PI, false));
        }
        let mut out = Vec::new();
        for (b, c, singular) in angles {
            if b < self.b_limits.0 - 1e-12 || b > self.b_limits.1 + 1e-12 {
                continue;
            }
            let c = wrap_angle(c);
            let tip_machine = self.machine_from_workpiece(b, c) * Point3::from(pose.tip);
            let gauge = tip_machine.coords + Vector3::z() * self.tool_length;
            out.push(FiveAxisSolution {
                joints: FiveAxisJoints {
                    d1: gauge.y,
                    d2: gauge.x,
                    d3: self.d0 - gauge.z,
                    b,
                    c,
                },
                singular,
            });
        }
        if out.is_empty() {
            return Err(KinematicsError::NoSolution {
                machine: "five-axis B/C table".into(),
                reason: format!("tool axis {k:?} needs B outside {:?} rad", self.b_limits),
            });
        }
        Ok(out)
    }
}

/// Wraps an angle to (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * PI);
    if w > PI {
        w - 2.0 * PI
    } else {
        w
    }
}
