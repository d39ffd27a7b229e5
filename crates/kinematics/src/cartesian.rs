//! Cartesian 3-axis machines in any stacking order (`XFYZ`, `FXYZ`, `XYFZ`, `XYZF`, `YXFZ`, ...), nominal
//! kinematics.
//!
//! Stacking string (thesis §3.1, Kiridena–Ferreira reading): the letters run from the workpiece to the tool and
//! `F` is the fixed frame (bed). Axes left of `F` move the workpiece, axes right of `F` move the tool; the
//! letter next to `F` sits on the bed, the outermost letter carries the workpiece (left end) or the tool (right
//! end). `XFYZ` (ANAYAK VH-1800): the X table carries the part; Y sits on the bed and carries Z, which carries
//! the tool. Note: the thesis calls the Alicona xy-stage "YXFZ" although its X rides on Y; in this reading
//! that stage is `XYFZ`.
//!
//! Axis coordinates follow ISO 841: `(x, y, z)` is the commanded motion of the tool relative to the workpiece,
//! so a workpiece-side axis physically moves its carriage by `−q` (thesis P5 eq. 7: `X = (−x + …)`).
//! Nominal forward kinematics is therefore the same for every stacking order:
//! `p_workpiece = q + tool_offset`, where `tool_offset` is the tool tip relative to the tool-carrying body at
//! zero, expressed in the bed frame (thesis `T = (x_t, y_t, z_t)`), and the workpiece frame coincides with the
//! bed frame at q = 0.

use crate::error::{check_finite, KinematicsError};
use nalgebra::Vector3;
use std::fmt;
use std::str::FromStr;

/// A linear machine axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LinearAxis {
    X,
    Y,
    Z,
}

impl LinearAxis {
    /// Index 0, 1, 2 for X, Y, Z.
    pub fn index(self) -> usize {
        match self {
            LinearAxis::X => 0,
            LinearAxis::Y => 1,
            LinearAxis::Z => 2,
        }
    }
    fn letter(self) -> char {
        ['X', 'Y', 'Z'][self.index()]
    }
}

/// Where each axis sits in the structure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StackingOrder {
    /// Workpiece-side axes from the bed outwards (index 0 sits on the bed).
    pub workpiece_side: Vec<LinearAxis>,
    /// Tool-side axes from the bed outwards (index 0 sits on the bed).
    pub tool_side: Vec<LinearAxis>,
}

impl FromStr for StackingOrder {
    type Err = KinematicsError;
    /// Parses strings such as `XFYZ` (case-insensitive): X, Y, Z and F, each exactly once.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |reason: &str| KinematicsError::StackingOrder {
            order: s.to_string(),
            reason: reason.to_string(),
        };
        let up: Vec<char> = s.trim().to_ascii_uppercase().chars().collect();
        if up.len() != 4 {
            return Err(err("must have exactly 4 letters: X, Y, Z and F"));
        }
        for c in ['X', 'Y', 'Z', 'F'] {
            match up.iter().filter(|&&u| u == c).count() {
                1 => {}
                0 => return Err(err(&format!("letter {c} is missing"))),
                _ => return Err(err(&format!("letter {c} appears more than once"))),
            }
        }
        if let Some(bad) = up.iter().find(|c| !matches!(c, 'X' | 'Y' | 'Z' | 'F')) {
            return Err(err(&format!("unexpected letter {bad}")));
        }
        let to_axis = |c: &char| match c {
            'X' => LinearAxis::X,
            'Y' => LinearAxis::Y,
            _ => LinearAxis::Z,
        };
        let f = up.iter().position(|&c| c == 'F').expect("checked");
        Ok(Self {
            workpiece_side: up[..f].iter().rev().map(to_axis).collect(),
            tool_side: up[f + 1..].iter().map(to_axis).collect(),
        })
    }
}

impl fmt::Display for StackingOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let left: String = self
            .workpiece_side
            .iter()
            .rev()
            .map(|a| a.letter())
            .collect();
        let right: String = self.tool_side.iter().map(|a| a.letter()).collect();
        write!(f, "{left}F{right}")
    }
}

impl StackingOrder {
    /// +1 if the axis moves the tool, −1 if it moves the workpiece (ISO 841 sign of the physical carriage
    /// motion for a positive axis coordinate).
    pub fn carriage_sign(&self, axis: LinearAxis) -> f64 {
        if self.workpiece_side.contains(&axis) {
            -1.0
        } else {
            1.0
        }
    }
}

/// A Cartesian 3-axis machine's nominal kinematics.
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianMachine {
    pub order: StackingOrder,
    /// Tool tip relative to the tool-carrying body at q = 0, bed frame (m).
    pub tool_offset: Vector3<f64>,
}

impl CartesianMachine {
    pub fn new(order: &str, tool_offset: Vector3<f64>) -> Result<Self, KinematicsError> {
        Ok(Self {
            order: order.parse()?,
            tool_offset,
        })
    }

    /// Nominal forward kinematics: tool tip in the workpiece frame for axis coordinates `q` (m).
    pub fn forward(&self, q: &Vector3<f64>) -> Result<Vector3<f64>, KinematicsError> {
        for (i, v) in q.iter().enumerate() {
            check_finite(["x", "y", "z"][i], *v)?;
        }
        Ok(q + self.tool_offset)
    }

    /// Nominal inverse kinematics: axis coordinates that put the tool tip at `p` (workpiece frame) (m).
    pub fn inverse(&self, p: &Vector3<f64>) -> Result<Vector3<f64>, KinematicsError> {
        for (i, v) in p.iter().enumerate() {
            check_finite(["x", "y", "z"][i], *v)?;
        }
        Ok(p - self.tool_offset)
    }
}
