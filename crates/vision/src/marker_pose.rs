//! Pose of a square marker from its four corners (the job of OpenCV's
//! `estimatePoseSingleMarkers` / `solvePnP(SOLVEPNP_IPPE_SQUARE)`), with covariance.
//!
//! Marker frame (OpenCV's): origin at the marker centre, x to the marker's right, y to its top,
//! z out of the printed face. Corner k (top-left, top-right, bottom-right, bottom-left) is at
//! (∓s/2, ±s/2, 0) as OpenCV: (−s/2, s/2), (s/2, s/2), (s/2, −s/2), (−s/2, −s/2).
//! The returned isometry maps marker → camera coordinates (metres).
//!
//! Method: homography of the undistorted corners → initial R, t (Zhang's decomposition), then
//! Gauss–Newton on the distorted reprojection error weighted by the corner covariances. The
//! pose covariance is (JᵀWJ)⁻¹ over (rotation vector increment [rad], translation [m]).

use crate::camera::{pixel_to_normalized, project, CameraModel};
use crate::error::{invalid, Result, VisionError};
use crate::homography::homography_4pt;
use nalgebra::{
    Isometry3, Matrix2, Matrix3, Point2, Point3, Rotation3, SMatrix, SVector, Translation3,
    UnitQuaternion, Vector3,
};

/// Estimated marker pose.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerPose {
    /// Marker → camera.
    pub camera_from_marker: Isometry3<f64>,
    /// 6×6 covariance of (δθ [rad] as a rotation vector applied on the left, t [m]).
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
/// (px) with covariances `corner_covariance` (px²); corners with a non-finite covariance get an
/// isotropic `fallback_sigma_px`.
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
    let obj = marker_object_points(side);
    let no_solution = |reason: &str| VisionError::NoSolution {
        what: "marker pose",
        reason: reason.to_string(),
    };
    // Initial pose from the homography model plane → normalised image plane.
    let mut norm = [[0.0; 2]; 4];
    for k in 0..4 {
        let (x, y) = pixel_to_normalized(camera, corners[k].x, corners[k].y)
            .ok_or_else(|| {
                no_solution("corner outside the distortion model's invertible region")
            })?;
        norm[k] = [x, y];
    }
    let model: [[f64; 2]; 4] = std::array::from_fn(|k| [obj[k].x, obj[k].y]);
    let h = homography_4pt(&model, &norm)
        .ok_or_else(|| no_solution("degenerate corner quadrilateral"))?;
    let (h1, h2, h3) = (
        h.column(0).into_owned(),
        h.column(1).into_owned(),
        h.column(2).into_owned(),
    );
    let mut lambda = 2.0 / (h1.norm() + h2.norm());
    if h3.z * lambda < 0.0 {
        lambda = -lambda;
    }
    let r1 = h1 * lambda;
    let r2 = h2 * lambda;
    let approx = Matrix3::from_columns(&[r1, r2, r1.cross(&r2)]);
    let svd = approx.svd(true, true);
    let (u, vt) = (
        svd.u.ok_or_else(|| no_solution("SVD failed"))?,
        svd.v_t.ok_or_else(|| no_solution("SVD failed"))?,
    );
    let mut rot = u * vt;
    if rot.determinant() < 0.0 {
        rot = -rot;
    }
    let mut r = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot));
    let mut t = h3 * lambda;

    // Whitening of each corner's residual: W_k = L_kᵀ L_k with L_k = chol(Σ_k)⁻¹.
    let whiten: Vec<Matrix2<f64>> = corner_covariance
        .iter()
        .map(|c| {
            let ok = c.iter().all(|v| v.is_finite());
            ok.then(|| c.cholesky().and_then(|ch| ch.l().try_inverse()))
                .flatten()
                .unwrap_or_else(|| Matrix2::identity() / fallback_sigma_px)
        })
        .collect();
    let residuals = |r: &UnitQuaternion<f64>, t: &Vector3<f64>| -> Option<SVector<f64, 8>> {
        let pose = Isometry3::from_parts(Translation3::from(*t), *r);
        let mut out = SVector::<f64, 8>::zeros();
        for k in 0..4 {
            let p = project(camera, &pose, &obj[k])?;
            let e = whiten[k] * (p - corners[k]);
            out[2 * k] = e.x;
            out[2 * k + 1] = e.y;
        }
        Some(out)
    };
    let perturb = |r: &UnitQuaternion<f64>, t: &Vector3<f64>, d: &SVector<f64, 6>| {
        (
            UnitQuaternion::from_scaled_axis(Vector3::new(d[0], d[1], d[2])) * r,
            t + Vector3::new(d[3], d[4], d[5]),
        )
    };
    let jacobian = |r: &UnitQuaternion<f64>, t: &Vector3<f64>| -> Option<SMatrix<f64, 8, 6>> {
        let mut j = SMatrix::<f64, 8, 6>::zeros();
        for i in 0..6 {
            let step = if i < 3 {
                1e-7
            } else {
                1e-7 * t.norm().max(1e-3)
            };
            let mut d = SVector::<f64, 6>::zeros();
            d[i] = step;
            let (rp, tp) = perturb(r, t, &d);
            d[i] = -step;
            let (rm, tm) = perturb(r, t, &d);
            j.set_column(
                i,
                &((residuals(&rp, &tp)? - residuals(&rm, &tm)?) / (2.0 * step)),
            );
        }
        Some(j)
    };
    let mut res = residuals(&r, &t).ok_or_else(|| no_solution("marker behind the camera"))?;
    for _ in 0..50 {
        let j = jacobian(&r, &t).ok_or_else(|| no_solution("marker behind the camera"))?;
        let step = (j.transpose() * j)
            .cholesky()
            .ok_or_else(|| no_solution("singular normal equations"))?
            .solve(&(-j.transpose() * res));
        let (rn, tn) = perturb(&r, &t, &step);
        let Some(resn) = residuals(&rn, &tn) else {
            break;
        };
        if resn.norm_squared() > res.norm_squared() {
            break;
        }
        (r, t, res) = (rn, tn, resn);
        if step.norm() < 1e-12 {
            break;
        }
    }
    let j = jacobian(&r, &t).ok_or_else(|| no_solution("marker behind the camera"))?;
    let covariance = (j.transpose() * j)
        .try_inverse()
        .ok_or_else(|| no_solution("pose not observable"))?;
    let pose = Isometry3::from_parts(Translation3::from(t), r);
    let sq: f64 = (0..4)
        .map(|k| {
            project(camera, &pose, &obj[k])
                .map_or(f64::NAN, |p| (p - corners[k]).norm_squared())
        })
        .sum();
    Ok(MarkerPose {
        camera_from_marker: pose,
        covariance,
        reprojection_rms_px: (sq / 4.0).sqrt(),
    })
}
