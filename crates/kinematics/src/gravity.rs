//! Gravity on a serial chain: where its links' masses are, the generalised force gravity exerts
//! on each joint variable, and the moment of what a link carries — what the gravity terms of the
//! physics catalog (crates/physics `gravity`) act on.
//!
//! Convention (stated once, here): g is the gravity vector in the chain's base frame, m/s²,
//! pointing down; a link's mass and centre of mass are its URDF `<inertial>` (the child link of
//! each joint, [`crate::serial::Joint::inertial`]). The generalised force on variable k is
//! τ_k = Σ_i m_i·gᵀ·∂c_i/∂q_k = −∂V/∂q_k (V = −Σ m_i gᵀ c_i): N·m for a revolute joint, N for a
//! prismatic one; a mimic's motion adds its multiplier's share to its master's.

use nalgebra::Vector3;

use crate::error::KinematicsError;
use crate::serial::{JointKind, SerialChain};

/// A link's mass at the chain's pose: the index of the joint whose child it is, its mass (kg)
/// and its centre of mass in the base frame (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlacedMass {
    pub joint: usize,
    pub mass: f64,
    pub centre: Vector3<f64>,
}

/// Every link with an inertial, placed at joint values `q`.
pub fn placed_masses(chain: &SerialChain, q: &[f64]) -> Result<Vec<PlacedMass>, KinematicsError> {
    let frames = chain.joint_frames(q)?;
    Ok(chain
        .joints
        .iter()
        .zip(&frames)
        .enumerate()
        .filter_map(|(i, (j, (_, child)))| {
            j.inertial.map(|m| PlacedMass {
                joint: i,
                mass: m.mass,
                centre: child
                    .transform_point(&nalgebra::Point3::from(m.centre_of_mass))
                    .coords,
            })
        })
        .collect())
}

/// τ_k of every joint variable (see the module docs) at `q` under gravity `g`.
pub fn gravity_torques(
    chain: &SerialChain,
    q: &[f64],
    g: &Vector3<f64>,
) -> Result<Vec<f64>, KinematicsError> {
    let frames = chain.joint_frames(q)?;
    let drives = chain.drives();
    let masses = placed_masses(chain, q)?;
    let mut tau = vec![0.0; chain.dof()];
    for (j, (joint, (before, _))) in chain.joints.iter().zip(&frames).enumerate() {
        let Some((k, factor)) = drives[j] else {
            continue;
        };
        let axis = before.rotation * joint.axis.into_inner();
        let origin = before.translation.vector;
        // every mass outboard of joint j moves with it
        for m in masses.iter().filter(|m| m.joint >= j) {
            let weight = g * m.mass;
            let moved = match joint.kind {
                JointKind::Revolute => axis.cross(&(m.centre - origin)),
                JointKind::Prismatic => axis,
                JointKind::Fixed => continue,
            };
            tau[k] += factor * moved.dot(&weight);
        }
    }
    Ok(tau)
}

/// The moment about `pivot` (base frame) of the weight of every link after joint `after` (the
/// child of joint `after` excluded: what that joint carries), N·m, base frame.
pub fn carried_moment(
    chain: &SerialChain,
    q: &[f64],
    g: &Vector3<f64>,
    after: usize,
    pivot: &Vector3<f64>,
) -> Result<Vector3<f64>, KinematicsError> {
    Ok(placed_masses(chain, q)?
        .iter()
        .filter(|m| m.joint > after)
        .map(|m| (m.centre - pivot).cross(&(g * m.mass)))
        .sum())
}
