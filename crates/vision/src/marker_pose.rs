//! Pose of a square marker from its four corners (the job of OpenCV's
//! `estimatePoseSingleMarkers` / `solvePnP(SOLVEPNP_IPPE_SQUARE)`), with covariance.
//!
//! Marker frame (OpenCV's): origin at the marker centre, x to the marker's right, y to its top,
//! z out of the printed face. Corner k (top-left, top-right, bottom-right, bottom-left) is at
//! (∓s/2, ±s/2, 0) as OpenCV: (−s/2, s/2), (s/2, s/2), (s/2, −s/2), (−s/2, −s/2).
//! The returned isometry maps marker → camera coordinates (metres).
//!
//! Method: homography of the undistorted corners → initial R, t (Zhang's decomposition), then
//! the workspace's Levenberg–Marquardt (metrocell_solver) on the distorted reprojection error
//! weighted by the corner covariances, with the camera model's analytic pose Jacobian. The pose
//! covariance is (JᵀWJ)⁻¹ over (rotation vector increment [rad], translation [m]).

use crate::camera::{pixel_to_normalized, pose_from_isometry, project, CameraModel};
use crate::error::{invalid, Result, VisionError};
use crate::homography::homography_4pt;
use metrocell_solver::{solve, NotEvaluable, Options, Problem, SolverError};
use nalgebra::{
    DMatrix, Isometry3, Matrix2, Matrix3, Point2, Point3, Rotation3, SMatrix, Translation3,
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
        let (x, y) = pixel_to_normalized(camera, corners[k].x, corners[k].y).ok_or_else(|| {
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
    let start = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot));
    let t = h3 * lambda;

    let problem = CornerReprojection {
        camera,
        object: obj,
        corners,
        whiten: std::array::from_fn(|k| {
            let c = &corner_covariance[k];
            let ok = c.iter().all(|v| v.is_finite());
            ok.then(|| c.cholesky().and_then(|ch| ch.l().try_inverse()))
                .flatten()
                .unwrap_or_else(|| Matrix2::identity() / fallback_sigma_px)
        }),
        start,
    };
    // Relative tolerances 1e-12: on 2000 simulated markers the pose then agrees with a solve to
    // round-off (1e-14) within 1 nm and 3e-8 rad, at half the evaluations. 50 iterations: the
    // slowest of them (43 px, seen 4.5° off face-on, where the two planar poses merge into a
    // shallow valley) stops there within 2e-11 of its minimum χ².
    let options = Options {
        max_iterations: 50,
        ftol: 1e-12,
        xtol: 1e-12,
        gtol: 1e-12,
        ..Options::default()
    };
    let fit = solve(&problem, &[0.0, 0.0, 0.0, t.x, t.y, t.z], &options).map_err(|e| match e {
        SolverError::StartNotEvaluable(_) => no_solution("marker behind the camera"),
        e => no_solution(&e.to_string()),
    })?;
    let covariance = fit
        .covariance_unscaled
        .map(|c| SMatrix::<f64, 6, 6>::from_iterator(c.iter().copied()))
        .ok_or_else(|| no_solution("pose not observable"))?;
    let pose = problem.pose(&fit.x);
    let sq: f64 = (0..4)
        .map(|k| {
            project(camera, &pose, &obj[k]).map_or(f64::NAN, |p| (p - corners[k]).norm_squared())
        })
        .sum();
    Ok(MarkerPose {
        camera_from_marker: pose,
        covariance,
        reprojection_rms_px: (sq / 4.0).sqrt(),
    })
}

/// The four corners' whitened reprojection errors Lₖ⁻¹·(project(pose, cornerₖ) − measuredₖ),
/// Σₖ = LₖLₖᵀ, so that the solver's plain least squares is the covariance-weighted one.
///
/// State x = (θ, t): θ the rotation vector of R·R₀⁻¹ relative to the homography's start R₀
/// (small, so never near the rotation vector's singularity at π, where markers facing the camera
/// sit), t in m. A step δ = (δθ, δt) is the perturbation of [`MarkerPose::covariance`], so the
/// solver's (J̃ᵀJ̃)⁻¹ is that covariance as it stands.
struct CornerReprojection<'a> {
    camera: &'a CameraModel,
    object: [Point3<f64>; 4],
    corners: &'a [Point2<f64>; 4],
    whiten: [Matrix2<f64>; 4],
    start: UnitQuaternion<f64>,
}

impl CornerReprojection<'_> {
    fn rotation(&self, x: &[f64]) -> UnitQuaternion<f64> {
        UnitQuaternion::from_scaled_axis(Vector3::new(x[0], x[1], x[2])) * self.start
    }

    fn pose(&self, x: &[f64]) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::new(x[3], x[4], x[5]), self.rotation(x))
    }
}

fn not_evaluable(e: metrocell_camera_model::CameraError) -> NotEvaluable {
    NotEvaluable(e.to_string())
}

impl Problem for CornerReprojection<'_> {
    fn residual_count(&self) -> usize {
        8
    }
    fn parameter_count(&self) -> usize {
        6
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> std::result::Result<(), NotEvaluable> {
        let pose = pose_from_isometry(&self.pose(x));
        for k in 0..4 {
            let [u, v] = self
                .camera
                .project(&pose, &self.object[k].coords)
                .map_err(not_evaluable)?;
            let e = self.whiten[k] * (Point2::new(u, v) - self.corners[k]);
            r[2 * k] = e.x;
            r[2 * k + 1] = e.y;
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> std::result::Result<(), NotEvaluable> {
        let pose = pose_from_isometry(&self.pose(x));
        for k in 0..4 {
            let p = self
                .camera
                .project_with_jacobians(&pose, &self.object[k].coords)
                .map_err(not_evaluable)?;
            let e = self.whiten[k] * (Point2::new(p.u, p.v) - self.corners[k]);
            r[2 * k] = e.x;
            r[2 * k + 1] = e.y;
            // the camera model's columns are (δt, δθ); ours (δθ, δt)
            let d = self.whiten[k] * p.d_pose;
            j.view_mut((2 * k, 0), (2, 3))
                .copy_from(&d.fixed_columns::<3>(3));
            j.view_mut((2 * k, 3), (2, 3))
                .copy_from(&d.fixed_columns::<3>(0));
        }
        Ok(())
    }
    fn retract(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(delta[0], delta[1], delta[2]))
            * self.rotation(x);
        let theta = (q * self.start.inverse()).scaled_axis();
        out[..3].copy_from_slice(theta.as_slice());
        for k in 3..6 {
            out[k] = x[k] + delta[k];
        }
    }
}
