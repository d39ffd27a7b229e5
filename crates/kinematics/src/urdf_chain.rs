//! Serial chains from URDF (via `urdf-rs`): the path of joints from a root link to a tip link.
//! Supported joint types: revolute, continuous (as revolute), prismatic, fixed. `<origin xyz rpy>` becomes the
//! joint's `pre` transform (URDF rpy: `Rz(yaw)·Ry(pitch)·Rx(roll)`), `<axis xyz>` its (normalised) axis
//! (URDF default `1 0 0`). Units are the URDF's own: metres and radians.
//!
//! Read into the chain as well: `<mimic joint multiplier offset>` (the joint follows another joint of the
//! path, `multiplier·q + offset`; it is then no variable of its own), `<limit lower upper>` of revolute and
//! prismatic joints, and each link's `<inertial>` mass and centre of mass (its `<origin xyz>`, in the link's
//! frame) — what gravity torques need. Refused with the joint's name, never ignored: a joint type that moves in
//! more than one degree of freedom (floating, planar) and a mimic of a joint that is not on the path.

use crate::error::KinematicsError;
use crate::serial::{Joint, JointKind, LinkInertial, Mimic, SerialChain};
use crate::transform::from_xyz_rpy;
use nalgebra::{Isometry3, Unit, Vector3};

/// Parses URDF text and builds the chain from `root_link` to `tip_link`.
pub fn chain_from_urdf_str(
    urdf: &str,
    root_link: &str,
    tip_link: &str,
) -> Result<SerialChain, KinematicsError> {
    let robot = urdf_rs::read_from_string(urdf).map_err(|e| KinematicsError::Urdf {
        reason: format!("parse error: {e}"),
    })?;
    chain_from_robot(&robot, root_link, tip_link)
}

/// Reads a URDF file and builds the chain from `root_link` to `tip_link`.
pub fn chain_from_urdf_file(
    path: &std::path::Path,
    root_link: &str,
    tip_link: &str,
) -> Result<SerialChain, KinematicsError> {
    let robot = urdf_rs::read_file(path).map_err(|e| KinematicsError::Urdf {
        reason: format!("{}: {e}", path.display()),
    })?;
    chain_from_robot(&robot, root_link, tip_link)
}

/// Builds the chain from `root_link` to `tip_link` of an already parsed robot.
pub fn chain_from_robot(
    robot: &urdf_rs::Robot,
    root_link: &str,
    tip_link: &str,
) -> Result<SerialChain, KinematicsError> {
    for name in [root_link, tip_link] {
        if !robot.links.iter().any(|l| l.name == name) {
            return Err(KinematicsError::Urdf {
                reason: format!("robot `{}` has no link `{name}`", robot.name),
            });
        }
    }
    let mut path = Vec::new();
    let mut link = tip_link.to_string();
    while link != root_link {
        let joint = robot
            .joints
            .iter()
            .find(|j| j.child.link == link)
            .ok_or_else(|| KinematicsError::Urdf {
                reason: format!(
                    "link `{tip_link}` is not below `{root_link}`: `{link}` has no parent joint"
                ),
            })?;
        path.push(joint);
        if path.len() > robot.joints.len() {
            return Err(KinematicsError::Urdf {
                reason: "joint graph has a cycle".into(),
            });
        }
        link = joint.parent.link.clone();
    }
    path.reverse();
    let names: Vec<String> = path.iter().map(|j| j.name.clone()).collect();
    let inertial_of = |link: &str| {
        robot.links.iter().find(|l| l.name == link).and_then(|l| {
            let mass = l.inertial.mass.value;
            (mass > 0.0 && mass.is_finite()).then(|| LinkInertial {
                mass,
                centre_of_mass: Vector3::from(l.inertial.origin.xyz.0),
            })
        })
    };
    let joints = path
        .into_iter()
        .map(|j| {
            let kind = match j.joint_type {
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                    JointKind::Revolute
                }
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                urdf_rs::JointType::Fixed => JointKind::Fixed,
                ref other => {
                    return Err(KinematicsError::Urdf {
                        reason: format!("joint `{}`: type {other:?} is not supported", j.name),
                    })
                }
            };
            let a = Vector3::from(j.axis.xyz.0);
            let axis = Unit::try_new(a, 1e-12).ok_or_else(|| KinematicsError::Urdf {
                reason: format!("joint `{}`: zero axis", j.name),
            })?;
            for (what, v) in [
                ("origin xyz", j.origin.xyz.0),
                ("origin rpy", j.origin.rpy.0),
                ("axis", j.axis.xyz.0),
            ] {
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(KinematicsError::Urdf {
                        reason: format!("joint `{}`: non-finite {what}", j.name),
                    });
                }
            }
            let mimic = match &j.mimic {
                None => None,
                Some(m) => {
                    let master = names.iter().position(|n| *n == m.joint).ok_or_else(|| KinematicsError::Urdf {
                        reason: format!("joint `{}` mimics `{}`, which is not on the chain from `{root_link}` to `{tip_link}`: a mimic needs its master on the same path", j.name, m.joint),
                    })?;
                    let (multiplier, offset) = (m.multiplier.unwrap_or(1.0), m.offset.unwrap_or(0.0));
                    if !(multiplier.is_finite() && offset.is_finite()) {
                        return Err(KinematicsError::Urdf { reason: format!("joint `{}`: non-finite mimic multiplier or offset", j.name) });
                    }
                    Some(Mimic { master, multiplier, offset })
                }
            };
            let limits = match kind {
                JointKind::Revolute if j.joint_type == urdf_rs::JointType::Continuous => None,
                JointKind::Revolute | JointKind::Prismatic if j.limit.upper > j.limit.lower => Some([j.limit.lower, j.limit.upper]),
                _ => None,
            };
            let mut joint = Joint::new(j.name.clone(), kind, from_xyz_rpy(j.origin.xyz.0, j.origin.rpy.0), axis, Isometry3::identity());
            joint.mimic = mimic;
            joint.limits = limits;
            joint.inertial = inertial_of(&j.child.link);
            Ok(joint)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SerialChain::new(joints))
}
