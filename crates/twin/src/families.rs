//! The five-axis and serial-arm machine families of the twin: their nominal chains built from the
//! cell file, the true chains with the kinematic error terms applied, and forward kinematics of
//! a program's joint vector to the tool point.
//!
//! Joint vectors (program targets, machine-state names), stated once here:
//! * five_axis: `[X, Y, Z, B, C]` named `x y z b c` (m, m, m, rad, rad), with X = DH d2,
//!   Y = DH d1, Z = −d3 (ISO: +Z lifts the tool off the table) of crates/kinematics
//!   `five_axis`. The tool point is the tool tip in the **workpiece** frame (it rotates with the
//!   table). Linear-axis error terms (machine-frame displacements, physics convention) act on the
//!   tip in the machine frame: `tip_wp = W(B, C)⁻¹·(tip_machine(X, Y, Z) + d)`.
//! * serial_arm: one value per movable joint, named as the DH rows (`joint_1` …) or the URDF
//!   joints. The tool point is `base · FK(q) · tool` in the cell frame (the frame of the tracker
//!   pose). The arm's kinematic terms: `joint_offset` q_i adds to movable joint i's variable;
//!   `link_length` l_i adds to the DH `a` of row i (the DH "link length"), or for a URDF chain
//!   lengthens joint i's `<origin xyz>` along itself. `tool_offset` on an arm is an error of the
//!   tool vector as mounted on the flange, so it turns with the tool: d = R_tool(q)·(dx, dy, dz).
//!
//! Tool frame (what a camera mount is relative to, see `ToolState` in the simulation): the
//! machine axes on a five-axis machine (the spindle does not turn; the workpiece does), the
//! arm's tool frame `base · FK(q) · tool` on an arm.

use std::path::Path;

use metrocell_kinematics::dh::{DhConvention, DhRow, DhTable};
use metrocell_kinematics::five_axis::FiveAxisGeometry;
use metrocell_kinematics::serial::{JointKind, SerialChain};
use metrocell_kinematics::urdf_chain::chain_from_urdf_file;
use nalgebra::Vector3;

use crate::cell::InstrumentPose;
use crate::cell_file::{DhConventionName, FiveAxisSection, JointKindName, SerialArmSection};
use crate::error::CellError;
use crate::quantity::{vector3, Quantity};

/// Names of the five-axis joint vector.
pub const FIVE_AXIS_JOINTS: [&str; 5] = ["x", "y", "z", "b", "c"];

/// A five-axis B/C table machine with its axis limits.
#[derive(Debug, Clone, PartialEq)]
pub struct FiveAxisMachine {
    pub geometry: FiveAxisGeometry,
    /// `[min, max]` of C (rad); B's are `geometry.b_limits`.
    pub c_limits: [f64; 2],
}

impl FiveAxisMachine {
    /// Tool tip in the machine frame for the linear axes (independent of B, C).
    pub fn tip_machine(&self, q: &[f64]) -> Vector3<f64> {
        Vector3::new(q[0], q[1], self.geometry.d0 + q[2] - self.geometry.tool_length)
    }
}

/// A serial arm: nominal chain (base and tool included), its DH table if it came from one.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialArm {
    pub chain: SerialChain,
    pub dh: Option<DhTable>,
    /// `[min, max]` per movable joint, if given.
    pub joint_limits: Option<Vec<[f64; 2]>>,
    /// Movable joints are revolute (true) or prismatic (false), in variable order.
    pub revolute: Vec<bool>,
}

impl SerialArm {
    pub fn joint_names(&self) -> Vec<String> {
        self.chain.variable_names()
    }

    /// Number of `link_length` parameters: DH rows or URDF joints (fixed ones included).
    pub fn link_count(&self) -> usize {
        self.chain.joints.len()
    }

    /// The chain with the true kinematic errors: `joint_offsets` per movable joint (rad or m),
    /// `link_lengths` per link (m), see the module doc.
    pub fn true_chain(&self, joint_offsets: &[f64], link_lengths: &[f64]) -> SerialChain {
        let mut chain = match &self.dh {
            Some(dh) => {
                let mut t = dh.clone();
                for (row, dl) in t.rows.iter_mut().zip(link_lengths) {
                    row.a += dl;
                }
                let mut c = t.to_chain();
                c.base = self.chain.base;
                c.tool = self.chain.tool;
                c
            }
            None => {
                let mut c = self.chain.clone();
                for (j, dl) in c.joints.iter_mut().zip(link_lengths) {
                    let v = j.pre.translation.vector;
                    let n = v.norm();
                    if n > 0.0 {
                        j.pre.translation.vector = v * ((n + dl) / n);
                    }
                }
                c
            }
        };
        let mut k = 0;
        for j in chain.joints.iter_mut() {
            if j.kind != JointKind::Fixed {
                j.offset += joint_offsets.get(k).copied().unwrap_or(0.0);
                k += 1;
            }
        }
        chain
    }
}

fn opt_vec(v: &Option<[Quantity; 3]>, path: &str) -> Result<Vector3<f64>, CellError> {
    v.as_ref().map(|v| vector3(v, path, "m")).transpose().map(|v| v.unwrap_or_else(Vector3::zeros))
}

fn limits(v: &Option<[Quantity; 2]>, path: &str, unit: &str, default: [f64; 2]) -> Result<[f64; 2], CellError> {
    let Some(v) = v else { return Ok(default) };
    let lo = v[0].to_si(&format!("{path}[0]"), unit)?;
    let hi = v[1].to_si(&format!("{path}[1]"), unit)?;
    if !(hi > lo) {
        return Err(CellError::invalid(path, format!("needs min < max, got [{lo}, {hi}] {unit}")));
    }
    Ok([lo, hi])
}

/// Validated five-axis geometry from `machine.five_axis`.
pub fn five_axis(s: &FiveAxisSection) -> Result<FiveAxisMachine, CellError> {
    let p = "machine.five_axis";
    let mut g = FiveAxisGeometry::new(s.d0.to_si(&format!("{p}.d0"), "m")?, s.tool_length.non_negative(&format!("{p}.tool_length"), "m")?);
    g.b_pivot = opt_vec(&s.b_pivot, &format!("{p}.b_pivot"))?;
    g.c_offset = opt_vec(&s.c_offset, &format!("{p}.c_offset"))?;
    g.workpiece_offset = opt_vec(&s.workpiece_offset, &format!("{p}.workpiece_offset"))?;
    let half = std::f64::consts::FRAC_PI_2;
    let b = limits(&s.b_limits, &format!("{p}.b_limits"), "rad", [-half, half])?;
    g.b_limits = (b[0], b[1]);
    let c_limits = limits(&s.c_limits, &format!("{p}.c_limits"), "rad", [-4.0 * half, 4.0 * half])?;
    Ok(FiveAxisMachine { geometry: g, c_limits })
}

/// Validated serial arm from `machine.serial_arm`; a URDF `path` is relative to `base_dir`.
pub fn serial_arm(s: &SerialArmSection, base_dir: &Path, pose: impl Fn(&crate::cell_file::PoseSection, &str) -> Result<InstrumentPose, CellError>) -> Result<SerialArm, CellError> {
    let p = "machine.serial_arm";
    let (mut chain, dh) = match (&s.dh, &s.urdf) {
        (Some(_), Some(_)) | (None, None) => return Err(CellError::invalid(p, "needs exactly one of `dh` (a DH table: {convention: standard | modified, rows}) and `urdf` ({path, root_link, tip_link})")),
        (Some(d), None) => {
            if d.rows.is_empty() {
                return Err(CellError::invalid(format!("{p}.dh.rows"), "needs at least one row {theta, d, a, alpha, joint: revolute | prismatic | fixed}"));
            }
            let mut rows = Vec::new();
            for (i, r) in d.rows.iter().enumerate() {
                let rp = format!("{p}.dh.rows[{i}]");
                let v = |q: &Option<Quantity>, name: &str, unit: &str| q.as_ref().map(|q| q.to_si(&format!("{rp}.{name}"), unit)).transpose().map(|v| v.unwrap_or(0.0));
                let (theta, dd, a, alpha) = (v(&r.theta, "theta", "rad")?, v(&r.d, "d", "m")?, v(&r.a, "a", "m")?, v(&r.alpha, "alpha", "rad")?);
                rows.push(match r.joint {
                    JointKindName::Revolute => DhRow::revolute(theta, dd, a, alpha),
                    JointKindName::Prismatic => DhRow::prismatic(theta, dd, a, alpha),
                    JointKindName::Fixed => DhRow::fixed(theta, dd, a, alpha),
                });
            }
            let convention = match d.convention {
                DhConventionName::Standard => DhConvention::Standard,
                DhConventionName::Modified => DhConvention::Modified,
            };
            let table = DhTable::new(convention, rows).map_err(|e| CellError::invalid(format!("{p}.dh"), e.to_string()))?;
            (table.to_chain(), Some(table))
        }
        (None, Some(u)) => {
            let path = base_dir.join(&u.path);
            let chain = chain_from_urdf_file(&path, &u.root_link, &u.tip_link).map_err(|e| CellError::invalid(format!("{p}.urdf"), format!("{e} (path resolved relative to the cell file: {})", path.display())))?;
            (chain, None)
        }
    };
    if chain.dof() == 0 {
        return Err(CellError::invalid(p, "the chain has no movable joint"));
    }
    if let Some(b) = &s.base {
        chain.base = pose(b, &format!("{p}.base"))?.isometry();
    }
    if let Some(t) = &s.tool {
        chain.tool = pose(t, &format!("{p}.tool"))?.isometry();
    }
    let revolute: Vec<bool> = chain.joints.iter().filter(|j| j.kind != JointKind::Fixed).map(|j| j.kind == JointKind::Revolute).collect();
    let joint_limits = if s.joint_limits.is_empty() {
        None
    } else {
        if s.joint_limits.len() != chain.dof() {
            return Err(CellError::invalid(format!("{p}.joint_limits"), format!("has {} entries; the arm has {} movable joints ({})", s.joint_limits.len(), chain.dof(), chain.variable_names().join(", "))));
        }
        let mut v = Vec::new();
        for (i, l) in s.joint_limits.iter().enumerate() {
            v.push(limits(&Some(l.clone()), &format!("{p}.joint_limits[{i}]"), if revolute[i] { "rad" } else { "m" }, [0.0, 0.0])?);
        }
        Some(v)
    };
    Ok(SerialArm { chain, dh, joint_limits, revolute })
}
