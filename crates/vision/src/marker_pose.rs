//! Pose of a square marker from its four corners (the job of OpenCV's
//! `estimatePoseSingleMarkers` / `solvePnP(SOLVEPNP_IPPE_SQUARE)`), with covariance.
//!
//! Marker frame (OpenCV's): origin at the marker centre, x to the marker's right, y to its top,
//! z out of the printed face. Corner k (top-left, top-right, bottom-right, bottom-left) is at
//! (∓s/2, ±s/2, 0) as OpenCV: (−s/2, s/2), (s/2, s/2), (s/2, −s/2), (−s/2, −s/2).
//! The returned isometry maps marker → camera coordinates (metres).
//!
//! Method: the workspace's one planar pose, crates/camera
//! `estimate_planar_pose_weighted` (IPPE's two solutions, each refined by Levenberg–Marquardt
//! on the distorted reprojection error weighted by the corner covariances, the better kept).
//! The pose covariance is (JᵀWJ)⁻¹ in the workspace's order, translation first (δt [m], δθ [rad]
//! as a rotation vector applied on the left, in the camera frame), as crates/camera states it.

use crate::camera::CameraModel;
use crate::error::{invalid, Result, VisionError};
use nalgebra::{Isometry3, Matrix2, Point2, Point3, SMatrix, Translation3, UnitQuaternion};

/// Estimated marker pose.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerPose {
    /// Marker → camera.
    pub camera_from_marker: Isometry3<f64>,
    /// 6×6 covariance of (t [m], δθ [rad] as a rotation vector applied on the left): translation
    /// first, the order of crates/camera's `PoseEstimate` and of geometry_msgs.
    pub covariance: SMatrix<f64, 6, 6>,
    /// RMS reprojection error of the four corners (px).
    pub reprojection_rms_px: f64,
}

/// Marker-frame corner positions for side `s` (m), OpenCV order.
pub fn marker_object_points(side: f64) -> [Point3<f64>; 4] {
    let h = side / 2.0;
    [
        Point3::new(-h, h, 0.0),
        Point3::new(h, h, 0.0),
        Point3::new(h, -h, 0.0),
        Point3::new(-h, -h, 0.0),
    ]
}

/// Estimate the pose of a marker of side `side` (m) whose corners were measured at `corners`
/// (px) with covariances `corner_covariance` (px²); corners with a non-finite (or not positive
/// definite) covariance get an isotropic `fallback_sigma_px`.
pub fn estimate_marker_pose(
    camera: &CameraModel,
    corners: &[Point2<f64>; 4],
    corner_covariance: &[Matrix2<f64>; 4],
    side: f64,
    fallback_sigma_px: f64,
) -> Result<MarkerPose> {
    if !(side.is_finite() && side > 0.0) {
        return Err(invalid(
            "side",
            format!("marker side must be finite and > 0 m, got {side}"),
        ));
    }
    if !(fallback_sigma_px.is_finite() && fallback_sigma_px > 0.0) {
        return Err(invalid(
            "fallback_sigma_px",
            format!("must be > 0, got {fallback_sigma_px}"),
        ));
    }
    for (k, c) in corners.iter().enumerate() {
        if !(c.x.is_finite() && c.y.is_finite()) {
            return Err(VisionError::NonFinite {
                what: "marker corners",
                index: k,
            });
        }
    }
    let object: Vec<[f64; 3]> = marker_object_points(side)
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect();
    let image: Vec<[f64; 2]> = corners.iter().map(|c| [c.x, c.y]).collect();
    let covariances: Vec<Matrix2<f64>> = corner_covariance
        .iter()
        .map(|c| {
            let usable = c.iter().all(|v| v.is_finite()) && c.cholesky().is_some();
            if usable {
                *c
            } else {
                Matrix2::identity() * (fallback_sigma_px * fallback_sigma_px)
            }
        })
        .collect();
    let est = metrocell_camera_model::estimate_planar_pose_weighted(
        camera,
        &object,
        &image,
        &covariances,
    )
    .map_err(|e| VisionError::NoSolution {
        what: "marker pose",
        reason: e.to_string(),
    })?;
    let rotation = UnitQuaternion::from_rotation_matrix(&est.pose.rotation);
    Ok(MarkerPose {
        camera_from_marker: Isometry3::from_parts(
            Translation3::from(est.pose.translation),
            rotation,
        ),
        covariance: est.covariance,
        reprojection_rms_px: est.rms_px,
    })
}
