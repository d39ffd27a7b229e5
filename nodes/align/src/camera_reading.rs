//! What the camera "reads" in seed 003's procedure, from the fiducial node's poses of a fixed
//! target: the camera's own displacement between two poses, in the first pose's camera axes,
//! from the target's *positions* only (as the patent's camera sees a point). The pose's
//! orientation is the noisiest part of a target pose — an error of 1e-4 rad is 0.04 mm at 0.4 m
//! — so the camera's turn is taken from what the robot was told to do instead.
//!
//! Convention (stated once): a pose is the target's in the camera's optical frame,
//! `p_c = R·p_t + t` (the fiducial node's `fiducials/pose`). The camera's origin moves by
//! `o₁ − o₀`; in the first camera axes that is `t₀ − R_rel·t₁` with `R_rel` the camera's turn
//! in its own first axes: the identity after a translation, `R_rcᵀ·R(θ)·R_rc` after a turn R(θ)
//! of the tool about a base axis, the camera's axes `R_rc` in the base's (the tool starting
//! with the base's axes).

use nalgebra::{Matrix3, Vector3};

/// The camera's displacement after a pure translation: the target's position before minus after.
pub fn displacement_after_translation(before: &Vector3<f64>, after: &Vector3<f64>) -> Vector3<f64> {
    before - after
}

/// The camera's displacement after the tool turned by `turn` (base axes), the camera's axes
/// being `r_rc` in the base's.
pub fn displacement_after_turn(
    before: &Vector3<f64>,
    after: &Vector3<f64>,
    r_rc: &Matrix3<f64>,
    turn: &Matrix3<f64>,
) -> Vector3<f64> {
    before - r_rc.transpose() * turn * r_rc * after
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion};

    /// Target at `target` (world), camera at `camera` (world pose): the target's pose in the camera.
    fn seen(camera: &Isometry3<f64>, target: &Isometry3<f64>) -> Isometry3<f64> {
        camera.inverse() * target
    }

    #[test]
    fn displacements_are_the_cameras_moves_in_its_first_axes() {
        let target = Isometry3::from_parts(
            Translation3::new(0.1, -0.2, 0.05),
            UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3),
        );
        // the tool starts with the base's axes: the camera's start orientation is R_rc
        let r0 = UnitQuaternion::from_euler_angles(3.0, 0.1, -0.4);
        let r_rc = *r0.to_rotation_matrix().matrix();
        let c0 = Isometry3::from_parts(Translation3::new(0.05, 0.02, 0.6), r0);
        let t = |c: &Isometry3<f64>| seen(c, &target).translation.vector;
        // a translation
        let v = Vector3::new(0.03, -0.01, 0.02);
        let c1 = Translation3::from(v) * c0;
        let d = displacement_after_translation(&t(&c0), &t(&c1));
        assert!((d - r0.inverse() * v).norm() < 1e-12);
        // a turn about an axis through a point
        let axis = Unit::new_normalize(Vector3::new(0.2, 0.1, 1.0));
        let turn = UnitQuaternion::from_axis_angle(&axis, 0.4);
        let a = Vector3::new(0.1, 0.0, 0.5);
        let c1 = Isometry3::from_parts((a + turn * (c0.translation.vector - a)).into(), turn * r0);
        let d =
            displacement_after_turn(&t(&c0), &t(&c1), &r_rc, turn.to_rotation_matrix().matrix());
        let truth = r0.inverse() * (c1.translation.vector - c0.translation.vector);
        assert!((d - truth).norm() < 1e-12, "{d} vs {truth}");
    }
}
