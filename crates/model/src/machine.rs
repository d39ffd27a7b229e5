//! The machine families' geometry: what the cell file's `machine` section becomes once
//! validated (crates/twin builds these), and what the forward model walks.
//!
//! Joint vectors (program targets, machine-state names), stated once here:
//! * cartesian, delta: `[x, y, z]` (m), the commanded tool position relative to the workpiece
//!   (ISO 841 / crates/kinematics); the nominal tool point is `q + tool_offset`.
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
//! Tool frame (what a camera mount is relative to, see [`crate::forward::ToolState`]): the
//! workpiece axes on cartesian and delta machines, the machine axes on a five-axis machine (the
//! spindle does not turn; the workpiece does), the arm's tool frame `base · FK(q) · tool` on an arm.

use metrocell_kinematics::cartesian::StackingOrder;
use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_kinematics::dh::DhTable;
use metrocell_kinematics::five_axis::FiveAxisGeometry;
use metrocell_kinematics::serial::SerialChain;
use nalgebra::Vector3;

/// The kinematic chain of the machine (crates/kinematics).
#[derive(Debug, Clone, PartialEq)]
pub enum MachineKinematics {
    /// Cartesian 3-axis machine in a stacking order.
    Cartesian(StackingOrder),
    /// Linear delta: the program's axis coordinates are the commanded effector position; the
    /// firmware's inverse kinematics uses this nominal geometry, the true geometry adds the
    /// `delta_*` terms' trims.
    Delta(DeltaGeometry),
    /// Five-axis B/C table; program joint vectors `[X, Y, Z, B, C]` (see [the module docs](self)).
    FiveAxis(FiveAxisMachine),
    /// Serial arm; program joint vectors hold one value per movable joint.
    SerialArm(SerialArm),
}

/// Nominal geometry of the machine.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineGeometry {
    pub kinematics: MachineKinematics,
    /// `[min, max]` of x, y, z (m): axis travels (Cartesian, five-axis X Y Z) or the effector
    /// box (delta); unbounded for a serial arm.
    pub travel: [[f64; 2]; 3],
    /// Tool tip (tracker target) relative to the tool-carrying body at q = 0 (m).
    pub tool_offset: Vector3<f64>,
}

impl MachineGeometry {
    /// Nominal forward kinematics (crates/kinematics convention, any stacking order; for a delta
    /// q is the effector position): tool tip in the workpiece frame, `q + tool_offset`.
    pub fn nominal_tool_point(&self, q: &Vector3<f64>) -> Vector3<f64> {
        q + self.tool_offset
    }

    /// The stacking order of a Cartesian machine.
    pub fn stacking(&self) -> Option<&StackingOrder> {
        match &self.kinematics {
            MachineKinematics::Cartesian(o) => Some(o),
            _ => None,
        }
    }

    /// Names of the joint vector the program and machine state use.
    pub fn joint_names(&self) -> Vec<String> {
        match &self.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) => {
                vec!["x".into(), "y".into(), "z".into()]
            }
            MachineKinematics::FiveAxis(_) => {
                FIVE_AXIS_JOINTS.iter().map(|s| s.to_string()).collect()
            }
            MachineKinematics::SerialArm(a) => a.joint_names(),
        }
    }

    /// Per joint: `[min, max]` and unit (`m` or `rad`), unbounded where the file gives no limit.
    pub fn joint_limits(&self) -> Vec<([f64; 2], &'static str)> {
        let inf = [f64::NEG_INFINITY, f64::INFINITY];
        match &self.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) => {
                self.travel.iter().map(|t| (*t, "m")).collect()
            }
            MachineKinematics::FiveAxis(f) => {
                let mut v: Vec<_> = self.travel.iter().map(|t| (*t, "m")).collect();
                v.push(([f.geometry.b_limits.0, f.geometry.b_limits.1], "rad"));
                v.push((f.c_limits, "rad"));
                v
            }
            MachineKinematics::SerialArm(a) => a
                .revolute
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    (
                        a.joint_limits.as_ref().map(|l| l[i]).unwrap_or(inf),
                        if *r { "rad" } else { "m" },
                    )
                })
                .collect(),
        }
    }

    /// True for the families whose joint vector is not the tool position (five_axis, serial_arm).
    pub fn is_jointed(&self) -> bool {
        matches!(
            self.kinematics,
            MachineKinematics::FiveAxis(_) | MachineKinematics::SerialArm(_)
        )
    }
}

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
        Vector3::new(
            q[0],
            q[1],
            self.geometry.d0 + q[2] - self.geometry.tool_length,
        )
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
    /// The accelerometers on the robot (the model file's `sensors.accelerometers`).
    pub accelerometers: Vec<ArmAccelerometer>,
}

/// An accelerometer on a robot: its name (`/imu/<name>`), the link it sits on, and — when that
/// link is fixed to the base (no joint variable between them) — the rotation of its frame in the
/// base frame, which turns its reading into the gravity of the base (the ground's tilt).
#[derive(Debug, Clone, PartialEq)]
pub struct ArmAccelerometer {
    pub name: String,
    pub link: String,
    pub base_from_sensor: Option<nalgebra::Matrix3<f64>>,
}

impl SerialArm {
    /// Gravity in the base frame from a reading of the base's accelerometer (specific force,
    /// its frame): straight down opposite the specific force, of standard magnitude; None
    /// without an accelerometer fixed to the base or its reading.
    pub fn gravity_from(
        &self,
        accelerations: &std::collections::BTreeMap<String, nalgebra::Vector3<f64>>,
    ) -> Option<nalgebra::Vector3<f64>> {
        self.accelerometers.iter().find_map(|a| {
            let r = a.base_from_sensor?;
            let f = accelerations.get(&a.name)?;
            let up = r * f;
            (up.norm() > 0.0)
                .then(|| -up.normalize() * metrocell_physics::gravity::STANDARD_GRAVITY)
        })
    }
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
        // one offset per joint variable (a mimic follows its master's, offset included)
        let mut k = 0;
        for j in chain.joints.iter_mut() {
            if j.is_variable() {
                j.offset += joint_offsets.get(k).copied().unwrap_or(0.0);
                k += 1;
            }
        }
        chain
    }
}
