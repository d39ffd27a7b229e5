//! What the camera calibration's own uncertainty adds to a pose.
//!
//! A pose is the least-squares fit of the target's reprojection to the detected corners with the
//! intrinsics k = (fx, fy, cx, cy, distortion coefficients…) taken as exact. They are not: the
//! calibration states their covariance Σ_k. To first order the fitted pose moves with k by
//! dδ/dk = −(J_δᵀJ_δ)⁻¹·J_δᵀ·J_k (J_δ, J_k: the reprojection's Jacobians w.r.t. the pose
//! perturbation of [`crate::pose`] and the intrinsics, at the fitted pose), so the pose
//! covariance gains A·Σ_k·Aᵀ with A = dδ/dk. A camera calibrated from a dozen views knows its
//! focal length to a few parts in 10⁴; a target half a metre away then moves by tens of µm along
//! the line of sight, far more than the corner noise alone says.

use nalgebra::{DMatrix, Matrix6, Vector3};

use crate::error::{invalid, Result};
use crate::model::CameraModel;
use crate::pose::Pose;

/// A·Σ_k·Aᵀ: the covariance (x, y, z, rot_x, rot_y, rot_z) the intrinsics' covariance
/// `intrinsics_covariance` (layout of [`CameraModel::params`]) adds to `pose` fitted to the
/// projections of `object` (target frame). Isotropic corner weights (what the pose fit uses).
pub fn pose_covariance_from_intrinsics(
    cam: &CameraModel,
    pose: &Pose,
    object: &[[f64; 3]],
    intrinsics_covariance: &DMatrix<f64>,
) -> Result<Matrix6<f64>> {
    let np = cam.n_params();
    if intrinsics_covariance.shape() != (np, np) {
        return Err(invalid(
            "intrinsics_covariance",
            format!(
                "is {}×{}, the camera model has {np} parameters (fx, fy, cx, cy, coefficients)",
                intrinsics_covariance.nrows(),
                intrinsics_covariance.ncols()
            ),
        ));
    }
    if !intrinsics_covariance.iter().all(|v| v.is_finite()) {
        return Err(invalid("intrinsics_covariance", "holds a non-finite value"));
    }
    let n = object.len();
    let mut j_pose = DMatrix::zeros(2 * n, 6);
    let mut j_k = DMatrix::zeros(2 * n, np);
    for (i, p) in object.iter().enumerate() {
        let pr = cam.project_with_jacobians(pose, &Vector3::from(*p))?;
        j_pose.view_mut((2 * i, 0), (2, 6)).copy_from(&pr.d_pose);
        j_k.view_mut((2 * i, 0), (2, 4)).copy_from(&pr.d_intrinsics);
        j_k.view_mut((2 * i, 4), (2, np - 4))
            .copy_from(&pr.d_distortion);
    }
    let normal = j_pose.transpose() * &j_pose;
    let inv = normal
        .try_inverse()
        .ok_or_else(|| invalid("pose", "not observable from these points (JᵀJ singular)"))?;
    let a = -(inv * j_pose.transpose() * j_k);
    let c = &a * intrinsics_covariance * a.transpose();
    Ok(Matrix6::from_fn(|r, k| 0.5 * (c[(r, k)] + c[(k, r)])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distortion::Distortion;

    /// The first-order sensitivity against refitting the pose with perturbed intrinsics.
    #[test]
    fn sensitivity_matches_refitting_with_perturbed_intrinsics() {
        let cam = CameraModel::new(
            800,
            600,
            700.0,
            705.0,
            405.3,
            296.8,
            Distortion::BrownConrady([-0.12, 0.05, 0.0, 0.0, 0.0]),
        )
        .unwrap();
        let pose = Pose::from_rvec_tvec([0.2, -0.3, 0.05], [-0.08, -0.05, 0.45]);
        let object: Vec<[f64; 3]> = (0..54)
            .map(|k| [(k % 9) as f64 * 0.025, (k / 9) as f64 * 0.025, 0.0])
            .collect();
        let image: Vec<[f64; 2]> = object
            .iter()
            .map(|p| cam.project(&pose, &Vector3::from(*p)).unwrap())
            .collect();
        // one parameter at a time: Σ_k = h² on its diagonal; A's column = the pose's move / h
        let h = [0.5, 0.5, 0.5, 0.5, 1e-3, 1e-3, 1e-4, 1e-4, 1e-3];
        for i in 0..cam.n_params() {
            let mut sigma = DMatrix::zeros(9, 9);
            sigma[(i, i)] = h[i] * h[i];
            let c = pose_covariance_from_intrinsics(&cam, &pose, &object, &sigma).unwrap();
            let mut p = cam.params();
            p[i] += h[i];
            let moved = cam.with_params(&p).unwrap();
            let refit = crate::estimate_planar_pose(&moved, &object, &image, 0.1)
                .unwrap()
                .pose;
            let dt = refit.translation - pose.translation;
            for axis in 0..3 {
                let predicted = c[(axis, axis)].sqrt();
                assert!(
                    (dt[axis].abs() - predicted).abs() <= 0.02 * predicted + 1e-9,
                    "parameter {i}, axis {axis}: refit moved {:e}, first order {:e}",
                    dt[axis],
                    predicted
                );
            }
        }
        assert!(
            pose_covariance_from_intrinsics(&cam, &pose, &object, &DMatrix::zeros(4, 4)).is_err()
        );
    }
}
