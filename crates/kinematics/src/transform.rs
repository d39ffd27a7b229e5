//! Elementary rigid transforms shared by every machine family.
//!
//! Convention (stated once for the crate): rotations are active and right-handed; a positive angle turns
//! counter-clockwise when looking from the tip of the axis towards the origin. `Isometry3` values named
//! `t_a_b` map coordinates expressed in frame `b` into frame `a` (`p_a = t_a_b * p_b`).
//! Roll–pitch–yaw follows URDF: `R = Rz(yaw) · Ry(pitch) · Rx(roll)` (fixed axes X, then Y, then Z).

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};

/// Rotation about the x axis by `angle` radians.
pub fn rot_x(angle: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), angle),
    )
}
/// Rotation about the y axis by `angle` radians.
pub fn rot_y(angle: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), angle),
    )
}
/// Rotation about the z axis by `angle` radians.
pub fn rot_z(angle: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle),
    )
}
/// Pure translation.
pub fn trans(x: f64, y: f64, z: f64) -> Isometry3<f64> {
    Isometry3::translation(x, y, z)
}
/// URDF origin: translation `xyz` then rotation `Rz(yaw)·Ry(pitch)·Rx(roll)`.
pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}
/// Skew-symmetric (cross-product) matrix: `skew(a) * b == a × b`.
pub fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}
/// Olinde–Rodrigues rotation of `angle` about the (normalised) `axis`:
/// `R = I cosθ + (1 − cosθ) u uᵀ + sinθ [u]×`.
pub fn rodrigues(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let u = axis.normalize();
    Matrix3::identity() * angle.cos()
        + (u * u.transpose()) * (1.0 - angle.cos())
        + skew(&u) * angle.sin()
}
/// Rotation about x by `a` (rad).
pub fn rx(a: f64) -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, a.cos(), -a.sin(), 0.0, a.sin(), a.cos())
}
/// Rotation about y by `a` (rad).
pub fn ry(a: f64) -> Matrix3<f64> {
    Matrix3::new(a.cos(), 0.0, a.sin(), 0.0, 1.0, 0.0, -a.sin(), 0.0, a.cos())
}
/// Rotation about z by `a` (rad).
pub fn rz(a: f64) -> Matrix3<f64> {
    Matrix3::new(a.cos(), -a.sin(), 0.0, a.sin(), a.cos(), 0.0, 0.0, 0.0, 1.0)
}
/// d[`rx`]/da.
pub fn drx(a: f64) -> Matrix3<f64> {
    Matrix3::new(
        0.0,
        0.0,
        0.0,
        0.0,
        -a.sin(),
        -a.cos(),
        0.0,
        a.cos(),
        -a.sin(),
    )
}
/// d[`ry`]/da.
pub fn dry(a: f64) -> Matrix3<f64> {
    Matrix3::new(
        -a.sin(),
        0.0,
        a.cos(),
        0.0,
        0.0,
        0.0,
        -a.cos(),
        0.0,
        -a.sin(),
    )
}
/// d[`rz`]/da.
pub fn drz(a: f64) -> Matrix3<f64> {
    Matrix3::new(
        -a.sin(),
        -a.cos(),
        0.0,
        a.cos(),
        -a.sin(),
        0.0,
        0.0,
        0.0,
        0.0,
    )
}
/// The project's one Euler-angle convention: intrinsic X-Y-Z, `R = Rx(α)·Ry(β)·Rz(δ)` (thesis P5
/// eq. 22). Every instrument pose, the `tracker_pose` term and the exact error chain build their
/// rotation here, so that they agree bit for bit.
pub fn euler_xyz(alpha: f64, beta: f64, delta: f64) -> Matrix3<f64> {
    rx(alpha) * ry(beta) * rz(delta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn rodrigues_matches_nalgebra_axis_angle() {
        let axis = Vector3::new(0.3, -0.5, 0.8);
        let r = rodrigues(&axis, 0.7);
        let n = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), 0.7)
            .into_inner();
        assert!((r - n).amax() < 1e-15);
    }

    #[test]
    fn urdf_rpy_is_fixed_axis_x_then_y_then_z() {
        let (roll, pitch, yaw) = (0.1, -0.4, 0.9);
        let t = from_xyz_rpy([1.0, 2.0, 3.0], [roll, pitch, yaw]);
        let expected = rot_z(yaw) * rot_y(pitch) * rot_x(roll);
        assert!(t.rotation.angle_to(&expected.rotation) < 1e-15);
        assert!((t * Point3::origin() - Point3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
    }

    #[test]
    fn positive_rotation_about_z_turns_x_into_y() {
        let p = rot_z(std::f64::consts::FRAC_PI_2) * Point3::new(1.0, 0.0, 0.0);
        assert!((p - Point3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
        assert!((skew(&Vector3::x()) * Vector3::y() - Vector3::z()).norm() == 0.0);
    }
}
