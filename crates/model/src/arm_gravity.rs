//! The gravity terms of a serial arm at one reading (crates/physics `gravity`): what they do to
//! the joints (per-variable offsets: a compliance's k·τ, a backlash's (b/2)·sign τ), what a
//! column's bending does to a point, and what their Jacobian columns need.
//!
//! Gravity comes from the reading's signals ([`Signals::gravity`], base frame, from the base's
//! accelerometer) or is straight down the base's −z. Torques and moments are taken at the
//! nominal chain and the commanded joints (first order: a deflection of a few mrad changes them
//! by as little). The column's pivots — its foot, each sliding segment's guide, the middle of its
//! tube — are the chain's own joint frames at the reading.

use metrocell_kinematics::gravity::{carried_moment, gravity_torques};
use metrocell_physics::config::Options;
use metrocell_physics::gravity::column_bending::ColumnBending;
use metrocell_physics::gravity::joint_backlash::JointBacklash;
use metrocell_physics::gravity::joint_compliance::JointCompliance;
use metrocell_physics::gravity::link_thermal_expansion::LinkThermalExpansion;
use metrocell_physics::gravity::STANDARD_GRAVITY;
use metrocell_physics::{PhysicsError, Signals, TermId};
use nalgebra::Vector3;

use crate::forward::ForwardModel;
use crate::machine::SerialArm;

/// A column's tilt per unit of each compliance: θ_k = c_k·axis_k about pivot_k.
#[derive(Debug, Clone)]
pub(crate) struct ColumnTilt {
    /// Index of the `column_bending` term among the machine terms.
    pub term: usize,
    /// The carried moment perpendicular to the column's axis, N·m (base frame).
    pub moment: Vector3<f64>,
    pub foot: Vector3<f64>,
    /// Each overlap's pivot and 1/o(e)².
    pub pads: Vec<(Vector3<f64>, f64)>,
    /// The tube's middle and its length L(e).
    pub middle: Vector3<f64>,
    pub length: f64,
}

impl ColumnTilt {
    /// The displacement of point `p` per unit of each of the three compliances (foot, pads,
    /// flexure).
    pub fn unit_effects(&self, p: &Vector3<f64>) -> [Vector3<f64>; 3] {
        let m = self.moment;
        let pads = self
            .pads
            .iter()
            .map(|(pivot, inv_o2)| (m * *inv_o2).cross(&(p - pivot)))
            .sum();
        [
            m.cross(&(p - self.foot)),
            pads,
            (m * self.length).cross(&(p - self.middle)),
        ]
    }
}

/// The gravity terms' state at one reading.
#[derive(Debug, Clone)]
pub(crate) struct ArmGravity {
    /// Per joint variable: the offset the compliance and backlash terms add to the command.
    pub offsets: Vec<f64>,
    /// The gravity torque on each variable.
    pub torques: Vec<f64>,
    /// (term index, its joints' variables) of `joint_compliance` and `joint_backlash` terms.
    pub compliance: Vec<(usize, Vec<usize>)>,
    pub backlash: Vec<(usize, Vec<usize>)>,
    pub column: Option<ColumnTilt>,
    /// (term index, T − 20 °C, the tool point's move per unit of α·(T − 20 °C): Σ_j ∂p/∂l_j·l_j)
    /// of a `link_thermal_expansion`.
    pub thermal: Option<(usize, f64, Vector3<f64>)>,
}

impl ArmGravity {
    /// The column's and the links' expansion's displacement of the true tool point `p` at
    /// parameters `params`.
    pub fn displacement(
        &self,
        model: &ForwardModel,
        params: &[f64],
        p: &Vector3<f64>,
    ) -> Vector3<f64> {
        let mut d = Vector3::zeros();
        if let Some(c) = &self.column {
            let k = model.part(c.term, params);
            let u = c.unit_effects(p);
            d += u[0] * k[0] + u[1] * k[1] + u[2] * k[2];
        }
        if let Some((term, dt, direction)) = self.thermal {
            d += direction * (model.part(term, params)[0] * dt);
        }
        d
    }

    /// The commanded joints with the gravity offsets added.
    pub fn deflected(&self, q: &[f64]) -> Vec<f64> {
        q.iter().zip(&self.offsets).map(|(a, b)| a + b).collect()
    }
}

fn variable_of(arm: &SerialArm, term: &str, joint: &str) -> Result<usize, PhysicsError> {
    let names = arm.chain.variable_names();
    names
        .iter()
        .position(|n| n == joint)
        .ok_or_else(|| PhysicsError::InvalidInput {
            what: format!("term `{term}`"),
            reason: format!(
                "joint `{joint}` is not one of the arm's joint variables ({})",
                names.join(", ")
            ),
        })
}

impl ForwardModel<'_> {
    /// The gravity terms' state at reading `q` (None when the model has none: the arm is rigid).
    pub(crate) fn arm_gravity(
        &self,
        arm: &SerialArm,
        p: &[f64],
        q: &[f64],
        s: &Signals,
    ) -> Result<Option<ArmGravity>, PhysicsError> {
        let ids = [
            TermId::JointCompliance,
            TermId::JointBacklash,
            TermId::ColumnBending,
            TermId::LinkThermalExpansion,
        ];
        if !self
            .machine_terms
            .terms
            .iter()
            .any(|t| ids.contains(&t.term.id()))
        {
            return Ok(None);
        }
        let kin = |e: metrocell_kinematics::error::KinematicsError| PhysicsError::InvalidInput {
            what: "gravity on the arm".into(),
            reason: e.to_string(),
        };
        let g = s
            .gravity
            .unwrap_or(Vector3::new(0.0, 0.0, -STANDARD_GRAVITY));
        let torques = gravity_torques(&arm.chain, q, &g).map_err(kin)?;
        let mut out = ArmGravity {
            offsets: vec![0.0; arm.chain.dof()],
            torques,
            compliance: Vec::new(),
            backlash: Vec::new(),
            column: None,
            thermal: None,
        };
        for (i, t) in self.machine_terms.terms.iter().enumerate() {
            let params = self.part(i, p);
            // the term's structure, from the options it was configured with
            let o = Options::new(t.term.id().as_str(), &t.options);
            match t.term.id() {
                TermId::JointCompliance | TermId::JointBacklash => {
                    let joints = match t.term.id() {
                        TermId::JointCompliance => JointCompliance::from_options(&o)?.joints,
                        _ => JointBacklash::from_options(&o)?.joints,
                    };
                    let vars = joints
                        .iter()
                        .map(|j| variable_of(arm, &t.term.label(), j))
                        .collect::<Result<Vec<_>, _>>()?;
                    for (v, k) in vars.iter().zip(params) {
                        let tau = out.torques[*v];
                        out.offsets[*v] += if t.term.id() == TermId::JointCompliance {
                            k * tau
                        } else {
                            0.5 * k * tau.signum()
                        };
                    }
                    if t.term.id() == TermId::JointCompliance {
                        out.compliance.push((i, vars));
                    } else {
                        out.backlash.push((i, vars));
                    }
                }
                TermId::ColumnBending => {
                    let c = ColumnBending::from_options(&o)?;
                    out.column = Some(self.column_tilt(arm, &c, i, q, &g)?);
                }
                TermId::LinkThermalExpansion => {
                    let c = LinkThermalExpansion::from_options(&o)?;
                    let dt = s.temperature(&t.term.label(), &c.sensor)? - 20.0;
                    // every joint's <origin xyz> (DH a, d) lengthens along itself
                    let oj = arm.chain.origin_translation_jacobian(q).map_err(kin)?;
                    let direction = arm
                        .chain
                        .joints
                        .iter()
                        .enumerate()
                        .map(|(k, joint)| {
                            oj.fixed_view::<3, 3>(0, 3 * k) * joint.pre.translation.vector
                        })
                        .sum();
                    out.thermal = Some((i, dt, direction));
                }
                _ => {}
            }
        }
        Ok(Some(out))
    }

    /// The column's moment, pivots and overlaps at `q`.
    fn column_tilt(
        &self,
        arm: &SerialArm,
        c: &ColumnBending,
        term: usize,
        q: &[f64],
        g: &Vector3<f64>,
    ) -> Result<ColumnTilt, PhysicsError> {
        let label = format!("column_bending[{}]", c.joint);
        let kin = |e: metrocell_kinematics::error::KinematicsError| PhysicsError::InvalidInput {
            what: format!("term `{label}`"),
            reason: e.to_string(),
        };
        let variable = variable_of(arm, &label, &c.joint)?;
        let drives = arm.chain.drives();
        let segments: Vec<(usize, f64)> = drives
            .iter()
            .enumerate()
            .filter_map(|(j, d)| d.filter(|(k, _)| *k == variable).map(|(_, f)| (j, f)))
            .collect();
        let frames = arm.chain.joint_frames(q).map_err(kin)?;
        let (first, last) = (segments[0].0, segments[segments.len() - 1].0);
        let foot = frames[first].0.translation.vector;
        let axis = frames[first].0.rotation * arm.chain.joints[first].axis.into_inner();
        let top = frames[last].1.translation.vector;
        let moment = carried_moment(&arm.chain, q, g, last, &top).map_err(kin)?;
        let moment = moment - axis * moment.dot(&axis);
        let e = q[variable];
        let mut pads = Vec::new();
        for (i, o0) in c.overlaps.iter().enumerate() {
            let Some(&(joint, share)) = segments.get(i) else {
                return Err(PhysicsError::InvalidInput {
                    what: format!("term `{label}`"),
                    reason: format!(
                        "{} overlaps given, the column has {} segments ({} and its mimics)",
                        c.overlaps.len(),
                        segments.len(),
                        c.joint
                    ),
                });
            };
            let o = o0 - share * e;
            if !(o > 0.0) {
                return Err(PhysicsError::InvalidInput { what: format!("term `{label}`"), reason: format!("segment {} has no overlap left at extension {e:.3} m (overlap {o0:.3} m at 0)", i + 1) });
            }
            pads.push((frames[joint].0.translation.vector, 1.0 / (o * o)));
        }
        // the tube's length: given at zero extension, or the chain's own at this reading
        let length = match c.length {
            Some(l0) => l0 + segments.iter().map(|(_, share)| share * e).sum::<f64>(),
            None => (top - foot).dot(&axis).abs(),
        };
        Ok(ColumnTilt {
            term,
            moment,
            foot,
            pads,
            middle: foot + axis * (0.5 * length),
            length,
        })
    }
}
