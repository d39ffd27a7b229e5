//! Gravity on arms and columns: how a serial robot (a mobile manipulator's lifting column and arm)
//! deflects under its own weight and what it carries, with the gravity vector of the instant
//! ([`crate::Signals::gravity`]: in the robot's base frame, from its base accelerometer — the
//! ground's tilt — or straight down the base's −z when the recording gives none).
//!
//! The terms are *kinematic*: their effect needs the robot's chain, its links' masses and centres of
//! mass (URDF `<inertial>`) and the joint values of the reading, which crates/model evaluates
//! (`ForwardModel`: the gravity torques of crates/kinematics `gravity`); here they carry their
//! parameters, equations and ranges:
//!
//! * [`joint_compliance`] — a joint yields by Δθ_j = k_j·τ_j to the gravity torque τ_j about it;
//! * [`joint_backlash`] — a joint's play b_j taken up to the side gravity pushes: Δθ_j =
//!   (b_j/2)·sign τ_j;
//! * [`column_bending`] — a telescoping column tilts under the moment of what it carries, at its foot,
//!   at each sliding overlap (shorter as it extends) and along its tube;
//! * [`link_thermal_expansion`] — every link of the chain lengthens with α·(T − 20 °C).
//!
//! Convention (stated once, here): the gravity torque τ_j is the generalised force gravity exerts on
//! joint variable j, τ_j = Σ_links m_i·gᵀ·∂c_i/∂q_j (N·m for a revolute joint, N for a prismatic one;
//! c_i the link's centre of mass, g pointing down): positive when gravity pulls the joint towards
//! positive values, and a compliant joint yields in that direction.

pub mod column_bending;
pub mod joint_backlash;
pub mod joint_compliance;
pub mod link_thermal_expansion;

use crate::config::Options;
use crate::error::PhysicsError;

/// Standard gravity, m/s² (the magnitude used when only a direction is known).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Gravity in the frame of a base tilted by (roll, pitch) from level, in `base_tilt`'s convention
/// (P_level = Rx(roll)·Ry(pitch)·P): g_B = (Rx·Ry)ᵀ·(0, 0, −g) = −g·(−sin p·cos r, sin r, cos p·cos r).
pub fn gravity_in_tilted_base(roll: f64, pitch: f64) -> nalgebra::Vector3<f64> {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    -STANDARD_GRAVITY * nalgebra::Vector3::new(-sp * cr, sr, cp * cr)
}

/// The inverse of [`gravity_in_tilted_base`]: the (roll, pitch) whose "up" in the base is the
/// direction `up` (any length > 0): roll = asin u_y, pitch = atan2(−u_x, u_z). None for a zero or
/// non-finite vector.
pub fn tilt_of_up(up: &nalgebra::Vector3<f64>) -> Option<(f64, f64)> {
    let n = up.norm();
    if !(n > 0.0 && n.is_finite()) {
        return None;
    }
    let u = up / n;
    Some((u.y.clamp(-1.0, 1.0).asin(), (-u.x).atan2(u.z)))
}

/// The joints a term acts on (option `joints`: a list of the chain's joint names).
pub(crate) fn joint_names(o: &Options) -> Result<Vec<String>, PhysicsError> {
    let items = o.get_list("joints")?.ok_or_else(|| o.bad("joints", "is required: the names of the joints it acts on, as the robot's URDF names them (e.g. [shoulder_lift, elbow])"))?;
    let mut out = Vec::new();
    for it in items {
        match it {
            crate::config::ConfigValue::Text(t)
                if !t.is_empty()
                    && t.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') =>
            {
                if out.contains(t) {
                    return Err(o.bad("joints", format!("`{t}` is given twice")));
                }
                out.push(t.clone());
            }
            other => return Err(o.bad("joints", format!("expected joint names, got {other:?}"))),
        }
    }
    if out.is_empty() {
        return Err(o.bad("joints", "names no joint"));
    }
    Ok(out)
}
