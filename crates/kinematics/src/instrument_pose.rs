//! The one pose type of an instrument (laser tracker, camera mount, arm base/tool).
//!
//! Frame convention, stated once for the whole project: a tracker's pose is given in the frame
//! the tool points are reported in — the **workpiece** frame on cartesian, delta and five-axis
//! machines (it coincides with the machine frame at q = 0; on a five-axis machine it turns with
//! the table), the cell (arm base) frame on a serial arm. `p_wp = R·p_inst + T`,
//! `R = Rx(α)·Ry(β)·Rz(δ)` (Euler XYZ, thesis P5 eq. 22), so the instrument reads
//! `X_inst = Rᵀ·(p_wp − T)` (thesis eq. 3.5). The catalog's parametrised form of the same pose
//! is the `tracker_pose` term (parameters tx ty tz alpha beta delta), whose prediction equals
//! [`InstrumentPose::to_instrument`] bit for bit ([`InstrumentPose::term_params`]).

use crate::transform::euler_xyz;
use nalgebra::{Matrix3, Vector3};

/// Pose of an instrument frame in the workpiece frame: `p_wp = rotation·p_inst + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstrumentPose {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
    /// The Euler XYZ angles `rotation` was built from (rad).
    pub euler_xyz: [f64; 3],
}

impl InstrumentPose {
    /// The identity: the instrument frame is the workpiece frame.
    pub fn identity() -> Self {
        Self::from_euler_xyz(Vector3::zeros(), [0.0; 3])
    }

    pub fn from_euler_xyz(translation: Vector3<f64>, e: [f64; 3]) -> Self {
        Self {
            rotation: euler_xyz(e[0], e[1], e[2]),
            translation,
            euler_xyz: e,
        }
    }
    /// The pose of a rotation matrix (proper, orthonormal) and translation, its Euler XYZ angles
    /// recovered from R = Rx(α)·Ry(β)·Rz(δ): β = asin R₀₂, α = atan2(−R₁₂, R₂₂),
    /// δ = atan2(−R₀₁, R₀₀) (β in [−90°, 90°]).
    pub fn from_rotation(translation: Vector3<f64>, rotation: &Matrix3<f64>) -> Self {
        let beta = rotation[(0, 2)].clamp(-1.0, 1.0).asin();
        let alpha = (-rotation[(1, 2)]).atan2(rotation[(2, 2)]);
        let delta = (-rotation[(0, 1)]).atan2(rotation[(0, 0)]);
        Self::from_euler_xyz(translation, [alpha, beta, delta])
    }

    /// Workpiece-frame point → instrument frame: `R_LTᵀ·(p − T_LT)` (thesis eq. 3.5, outer part).
    pub fn to_instrument(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation.transpose() * (p - self.translation)
    }

    /// The `tracker_pose` term's parameters (tx, ty, tz, alpha, beta, delta) of this pose.
    pub fn term_params(&self) -> [f64; 6] {
        let (t, e) = (self.translation, self.euler_xyz);
        [t.x, t.y, t.z, e[0], e[1], e[2]]
    }

    /// The pose as an isometry (`rotation` is a proper rotation, built from Euler angles).
    pub fn isometry(&self) -> nalgebra::Isometry3<f64> {
        let r = nalgebra::Rotation3::from_matrix_unchecked(self.rotation);
        nalgebra::Isometry3::from_parts(
            self.translation.into(),
            nalgebra::UnitQuaternion::from_rotation_matrix(&r),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_angles_round_trip_through_the_rotation() {
        for e in [[0.1, -0.4, 2.5], [-3.0, 1.2, -0.3], [0.0, 0.0, 0.0]] {
            let p = InstrumentPose::from_euler_xyz(Vector3::new(1.0, 2.0, 3.0), e);
            let q = InstrumentPose::from_rotation(p.translation, &p.rotation);
            assert!(
                (q.rotation - p.rotation).abs().max() < 1e-14,
                "{e:?} -> {:?}",
                q.euler_xyz
            );
            for k in 0..3 {
                assert!(
                    (q.euler_xyz[k] - e[k]).abs() < 1e-12,
                    "{e:?} -> {:?}",
                    q.euler_xyz
                );
            }
        }
    }
}
