//! Rigid pose of a target in the camera frame and its 6-parameter perturbation.
//!
//! Frames (OpenCV): camera x right, y down, z forward along the optical axis. A [`Pose`] maps
//! target coordinates to camera coordinates: X_cam = R·X_target + t (t in metres if the target is
//! in metres). This is OpenCV's (rvec, tvec), and as a ROS pose it is the target frame expressed in
//! the camera frame (parent = camera).
//!
//! Perturbation convention (used by every Jacobian and covariance in this crate): a 6-vector
//! δ = (δx, δy, δz, δθx, δθy, δθz) updates the pose as
//!   t ← t + (δx, δy, δz),   R ← exp(\[δθ\]×)·R,
//! i.e. a small rotation about the *camera (parent) frame's fixed* x, y, z axes applied on the
//! left, and a translation in the camera frame. This is the ordering and meaning of
//! geometry_msgs/PoseWithCovariance (x, y, z, rotation about X, rotation about Y, rotation about Z,
//! all in the parent frame).

use nalgebra::{Matrix3, Rotation3, Vector3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub rotation: Rotation3<f64>,
    pub translation: Vector3<f64>,
}

impl Pose {
    pub fn identity() -> Self {
        Pose {
            rotation: Rotation3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// From OpenCV's Rodrigues rotation vector (axis·angle, rad) and translation.
    pub fn from_rvec_tvec(rvec: [f64; 3], tvec: [f64; 3]) -> Self {
        Pose {
            rotation: Rotation3::from_scaled_axis(Vector3::from(rvec)),
            translation: Vector3::from(tvec),
        }
    }

    /// OpenCV rotation vector (axis·angle, rad, angle in [0, π]).
    pub fn rvec(&self) -> [f64; 3] {
        let v = self.rotation.scaled_axis();
        [v.x, v.y, v.z]
    }

    pub fn tvec(&self) -> [f64; 3] {
        [self.translation.x, self.translation.y, self.translation.z]
    }

    /// Target point → camera frame.
    pub fn transform(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }

    /// The pose as the solver's flat state (t, rvec): translation (m), then rotation vector (rad).
    pub(crate) fn to_state(self) -> [f64; 6] {
        let r = self.rvec();
        [
            self.translation.x,
            self.translation.y,
            self.translation.z,
            r[0],
            r[1],
            r[2],
        ]
    }

    /// Inverse of [`Self::to_state`] (the first six values of `x`).
    pub(crate) fn from_state(x: &[f64]) -> Pose {
        Pose::from_rvec_tvec([x[3], x[4], x[5]], [x[0], x[1], x[2]])
    }

    /// Applies the perturbation δ = (δt, δθ) of the module-level convention.
    pub fn perturbed(&self, delta: &[f64]) -> Pose {
        let dt = Vector3::new(delta[0], delta[1], delta[2]);
        let dth = Vector3::new(delta[3], delta[4], delta[5]);
        Pose {
            rotation: Rotation3::from_scaled_axis(dth) * self.rotation,
            translation: self.translation + dt,
        }
    }

    /// Rotation as a unit quaternion (x, y, z, w), the ROS order.
    pub fn quaternion_xyzw(&self) -> [f64; 4] {
        let q = nalgebra::UnitQuaternion::from_rotation_matrix(&self.rotation);
        [q.i, q.j, q.k, q.w]
    }
}

/// Skew-symmetric matrix with \[v\]×·w = v × w.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rvec_round_trip_and_left_perturbation() {
        let p = Pose::from_rvec_tvec([0.1, -0.4, 0.25], [0.01, 0.02, 0.5]);
        let r = p.rvec();
        assert!(
            (r[0] - 0.1).abs() < 1e-14 && (r[1] + 0.4).abs() < 1e-14 && (r[2] - 0.25).abs() < 1e-14
        );
        // A rotation of 0.01 rad about the camera z axis moves R·X by δθ × (R·X).
        let x = Vector3::new(0.03, -0.02, 0.0);
        let q = p.perturbed(&[0.0, 0.0, 0.0, 0.0, 0.0, 1e-6]);
        let moved = q.rotation * x - p.rotation * x;
        let expect = Vector3::new(0.0, 0.0, 1e-6).cross(&(p.rotation * x));
        assert!(
            (moved - expect).norm() < 1e-13,
            "{}",
            (moved - expect).norm()
        );
    }
}
