//! Zhang calibration of a camera from views of a planar target (object points on z = 0):
//! per-view normalised-DLT homographies → closed-form intrinsics → per-view poses → one
//! Levenberg–Marquardt over every free parameter (intrinsics, distortion, all poses) with analytic
//! Jacobians → parameter covariance (JᵀJ)⁻¹·σ², σ² = Σ r² / (2N − P) (N points, P free parameters;
//! per image coordinate). Views are rejected, with a reason, for too few points, a non-planar target,
//! a degenerate homography or pose, and (after a first full pass) a view RMS above k × median.
//!
//! RMS values follow OpenCV: sqrt(Σ‖r_i‖² / N), the RMS of the reprojection *distance* (pixels).
//! The standard deviations equal OpenCV 5.0's `stdDeviationsIntrinsics` on the same data (tested).

use crate::distortion::Distortion;
use crate::error::{invalid, CameraError, Result};
use crate::homography::homography_dlt;
use crate::model::CameraModel;
use crate::pose::Pose;
use crate::pose_estimation::refine_pose;
use crate::solver_bridge::{not_evaluable, solve_pixels};
use crate::zhang::{focal_from_homographies, intrinsics_from_homographies, pose_from_homography};
use metrocell_solver::{NotEvaluable, Problem};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// One image of the target: corresponding target points (z = 0) and pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    pub object_points: Vec<[f64; 3]>,
    pub image_points: Vec<[f64; 2]>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LensModel {
    /// (k1, k2, p1, p2, k3), `cv::calibrateCamera`.
    BrownConrady,
    /// (k1, k2, k3, k4), `cv::fisheye::calibrate` with CALIB_FIX_SKEW.
    Fisheye,
}

#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationFlags {
    /// Keep (cx, cy) at the guess, or at ((w−1)/2, (h−1)/2) without a guess.
    pub fix_principal_point: bool,
    /// Keep fx/fy at the guess's ratio (1 without a guess).
    pub fix_aspect_ratio: bool,
    /// Brown–Conrady only: p1 = p2 = 0 fixed.
    pub zero_tangential: bool,
    /// Indices into the distortion coefficients held at their initial value (0 without a guess),
    /// e.g. `vec![4]` fixes k3 (OpenCV CALIB_FIX_K3).
    pub fixed_distortion: Vec<usize>,
    /// Start from this model (OpenCV CALIB_USE_INTRINSIC_GUESS); its lens model must match.
    pub initial_guess: Option<CameraModel>,
    /// Views with fewer points are rejected (minimum 4).
    pub min_points_per_view: usize,
    /// After a first pass, reject views whose RMS exceeds this multiple of the median view RMS…
    pub outlier_view_ratio: Option<f64>,
    /// …and also exceeds this absolute floor (pixels).
    pub outlier_view_min_rms_px: f64,
    pub max_iterations: usize,
}

impl Default for CalibrationFlags {
    fn default() -> Self {
        CalibrationFlags {
            fix_principal_point: false,
            fix_aspect_ratio: false,
            zero_tangential: false,
            fixed_distortion: Vec::new(),
            initial_guess: None,
            min_points_per_view: 8,
            outlier_view_ratio: Some(3.0),
            outlier_view_min_rms_px: 0.0,
            max_iterations: 200,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum RejectionReason {
    TooFewPoints {
        got: usize,
        needed: usize,
    },
    MismatchedPoints {
        object: usize,
        image: usize,
    },
    NonFinitePoint {
        index: usize,
    },
    NotOnPlaneZ0 {
        index: usize,
        z: f64,
    },
    DegenerateHomography(String),
    PoseInitialisation(String),
    OutlierRms {
        rms_px: f64,
        median_rms_px: f64,
        ratio_limit: f64,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct RejectedView {
    /// Index into the input `views`.
    pub index: usize,
    pub reason: RejectionReason,
}

#[derive(Debug, Clone, PartialEq)]
pub struct CalibratedView {
    /// Index into the input `views`.
    pub index: usize,
    /// Target → camera.
    pub pose: Pose,
    /// Standard uncertainties of (x, y, z, rot_x, rot_y, rot_z), convention of [`crate::pose`].
    pub pose_std: [f64; 6],
    /// sqrt(Σ‖r‖²/n) for this view (pixels), OpenCV's perViewErrors.
    pub rms_px: f64,
    pub n_points: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    pub camera: CameraModel,
    /// Standard uncertainty of each entry of `camera.params()` (fx, fy, cx, cy, coefficients…);
    /// 0 for fixed parameters.
    pub param_std: Vec<f64>,
    /// Covariance of `camera.params()` (fixed parameters have zero rows/columns).
    pub param_covariance: DMatrix<f64>,
    pub views: Vec<CalibratedView>,
    pub rejected: Vec<RejectedView>,
    /// Overall sqrt(Σ‖r‖²/N) over the used views (pixels), OpenCV's return value.
    pub rms_px: f64,
    /// Estimated per-coordinate corner noise sqrt(Σr²/(2N − P)) (pixels).
    pub sigma_px: f64,
    pub n_points: usize,
    pub n_free_params: usize,
    pub iterations: usize,
}

/// Maps a reduced (free) intrinsic perturbation to the full (fx, fy, cx, cy, coeffs) one.
fn intrinsic_map(
    n_dist: usize,
    model: LensModel,
    flags: &CalibrationFlags,
    aspect: f64,
) -> DMatrix<f64> {
    let n = 4 + n_dist;
    let mut cols: Vec<DVector<f64>> = Vec::new();
    let unit = |i: usize| {
        let mut v = DVector::zeros(n);
        v[i] = 1.0;
        v
    };
    if flags.fix_aspect_ratio {
        let mut v = unit(0);
        v[1] = 1.0 / aspect; // fy = fx / aspect, aspect = fx/fy
        cols.push(v);
    } else {
        cols.push(unit(0));
        cols.push(unit(1));
    }
    if !flags.fix_principal_point {
        cols.push(unit(2));
        cols.push(unit(3));
    }
    for d in 0..n_dist {
        let tangential = model == LensModel::BrownConrady && (d == 2 || d == 3);
        if flags.fixed_distortion.contains(&d) || (tangential && flags.zero_tangential) {
            continue;
        }
        cols.push(unit(4 + d));
    }
    DMatrix::from_columns(&cols)
}

/// (object points, image points) of one view.
type Correspondences<'a> = (&'a [[f64; 3]], &'a [[f64; 2]]);

/// Flat state: the free intrinsics as offsets from `base` through the map `t` (full parameters
/// = base + t·x[..ni]), then each view's pose as (t, rvec); steps on the poses are the
/// perturbation δ of [`crate::pose`].
struct CalibrationProblem<'a> {
    views: Vec<Correspondences<'a>>,
    t: DMatrix<f64>,
    base: CameraModel,
    base_params: DVector<f64>,
    n_points: usize,
}

impl CalibrationProblem<'_> {
    fn camera(&self, x: &[f64]) -> CameraModel {
        let ni = self.t.ncols();
        let p = &self.base_params + &self.t * DVector::from_column_slice(&x[..ni]);
        self.base.with_params_unchecked(p.as_slice())
    }

    fn pose(&self, x: &[f64], v: usize) -> Pose {
        Pose::from_state(&x[self.t.ncols() + 6 * v..])
    }
}

impl Problem for CalibrationProblem<'_> {
    fn residual_count(&self) -> usize {
        2 * self.n_points
    }
    fn parameter_count(&self) -> usize {
        self.t.ncols() + 6 * self.views.len()
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> std::result::Result<(), NotEvaluable> {
        let cam = self.camera(x);
        let mut row = 0;
        for (v, (obj, img)) in self.views.iter().enumerate() {
            let pose = self.pose(x, v);
            for (o, m) in obj.iter().zip(img.iter()) {
                let [u, w] = cam
                    .project(&pose, &Vector3::from(*o))
                    .map_err(not_evaluable)?;
                r[row] = u - m[0];
                r[row + 1] = w - m[1];
                row += 2;
            }
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> std::result::Result<(), NotEvaluable> {
        let cam = self.camera(x);
        let ni = self.t.ncols();
        let nfull = self.t.nrows();
        j.fill(0.0);
        let mut full = DMatrix::zeros(2, nfull);
        let mut row = 0;
        for (v, (obj, img)) in self.views.iter().enumerate() {
            let pose = self.pose(x, v);
            for (o, m) in obj.iter().zip(img.iter()) {
                let pr = cam
                    .project_with_jacobians(&pose, &Vector3::from(*o))
                    .map_err(not_evaluable)?;
                r[row] = pr.u - m[0];
                r[row + 1] = pr.v - m[1];
                full.view_mut((0, 0), (2, 4)).copy_from(&pr.d_intrinsics);
                full.view_mut((0, 4), (2, nfull - 4))
                    .copy_from(&pr.d_distortion);
                j.view_mut((row, 0), (2, ni)).copy_from(&(&full * &self.t));
                j.view_mut((row, ni + 6 * v), (2, 6)).copy_from(&pr.d_pose);
                row += 2;
            }
        }
        Ok(())
    }
    fn retract(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        let ni = self.t.ncols();
        for k in 0..ni {
            out[k] = x[k] + delta[k];
        }
        for v in 0..self.views.len() {
            let at = ni + 6 * v;
            out[at..at + 6]
                .copy_from_slice(&self.pose(x, v).perturbed(&delta[at..at + 6]).to_state());
        }
    }
}

/// The fitted state and what the covariance needs.
struct Fit {
    cam: CameraModel,
    poses: Vec<Pose>,
    residuals: DVector<f64>,
    /// (JᵀJ)⁻¹ over the free parameters; None if they are not all observable.
    normal_inverse: Option<DMatrix<f64>>,
    iterations: usize,
}

fn validate_view(view: &View, min_points: usize) -> std::result::Result<(), RejectionReason> {
    let (no, ni) = (view.object_points.len(), view.image_points.len());
    if no != ni {
        return Err(RejectionReason::MismatchedPoints {
            object: no,
            image: ni,
        });
    }
    if no < min_points {
        return Err(RejectionReason::TooFewPoints {
            got: no,
            needed: min_points,
        });
    }
    let extent = view
        .object_points
        .iter()
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(0.0, f64::max);
    for (i, (o, m)) in view
        .object_points
        .iter()
        .zip(&view.image_points)
        .enumerate()
    {
        if o.iter().chain(m.iter()).any(|x| !x.is_finite()) {
            return Err(RejectionReason::NonFinitePoint { index: i });
        }
        if o[2].abs() > 1e-9 * extent {
            return Err(RejectionReason::NotOnPlaneZ0 { index: i, z: o[2] });
        }
    }
    Ok(())
}

fn run_lm(
    views: &[(usize, &View)],
    cam: CameraModel,
    poses: Vec<Pose>,
    t: &DMatrix<f64>,
    max_it: usize,
) -> Result<Fit> {
    let problem = CalibrationProblem {
        views: views
            .iter()
            .map(|(_, v)| (v.object_points.as_slice(), v.image_points.as_slice()))
            .collect(),
        t: t.clone(),
        base_params: DVector::from_vec(cam.params()),
        base: cam,
        n_points: views.iter().map(|(_, v)| v.object_points.len()).sum(),
    };
    let mut x0 = vec![0.0; t.ncols()];
    x0.extend(poses.iter().flat_map(|p| p.to_state()));
    let out = solve_pixels(&problem, &x0, max_it, "calibration")?;
    Ok(Fit {
        cam: problem.camera(&out.x),
        poses: (0..views.len()).map(|v| problem.pose(&out.x, v)).collect(),
        residuals: DVector::from_vec(out.residuals),
        normal_inverse: out.covariance_unscaled,
        iterations: out.iterations,
    })
}

fn view_rms(res: &DVector<f64>, views: &[(usize, &View)]) -> Vec<f64> {
    let mut row = 0;
    views
        .iter()
        .map(|(_, v)| {
            let n = v.object_points.len();
            let s = res.rows(row, 2 * n).norm_squared();
            row += 2 * n;
            (s / n as f64).sqrt()
        })
        .collect()
}

/// Calibrates a camera of `image_size` (width, height) from planar-target views.
///
/// The settings are checked; each view's homography is estimated (a degenerate view rejected
/// with the reason), the intrinsics initialised from them (Zhang) and each view's pose; one
/// bundle adjustment, and a second without the outlier views; the covariance scaled by the
/// residuals' σ.
pub fn calibrate(
    views: &[View],
    image_size: (u32, u32),
    model: LensModel,
    flags: &CalibrationFlags,
) -> Result<Calibration> {
    let (w, h) = image_size;
    let n_dist = checked_settings(image_size, model, flags)?;
    let mut rejected = Vec::new();
    let usable = view_homographies(views, flags, &mut rejected);
    if usable.is_empty() {
        return Err(CameraError::NoUsableViews(format!(
            "{} views given, all rejected: {:?}",
            views.len(),
            rejected
        )));
    }
    let hs: Vec<Matrix3<f64>> = usable.iter().map(|u| u.2).collect();
    let mut cam = initial_camera(&hs, w, h, model, flags)?;
    cam.width = w;
    cam.height = h;
    let aspect = cam.fx / cam.fy;
    // Initial poses: homography decomposition, then per-view refinement with the initial camera.
    let k = cam.k_matrix();
    let mut used: Vec<(usize, &View)> = Vec::new();
    let mut poses = Vec::new();
    for (i, v, hm) in &usable {
        let p = pose_from_homography(hm, &k)
            .and_then(|p0| refine_pose(&cam, &v.object_points, &v.image_points, p0).map(|r| r.0));
        match p {
            Ok(p) => {
                used.push((*i, *v));
                poses.push(p);
            }
            Err(e) => rejected.push(RejectedView {
                index: *i,
                reason: RejectionReason::PoseInitialisation(e.to_string()),
            }),
        }
    }
    if used.is_empty() {
        return Err(CameraError::NoUsableViews(format!(
            "no view survived pose initialisation: {rejected:?}"
        )));
    }
    let t = intrinsic_map(n_dist, model, flags, aspect);
    let mut fit = run_lm(&used, cam, poses, &t, flags.max_iterations)?;
    // Outlier views after the first pass.
    if let Some(kratio) = flags.outlier_view_ratio {
        let bad = outlier_views(&fit, &used, kratio, flags, &mut rejected);
        if !bad.is_empty() && bad.len() < used.len() {
            let keep: Vec<usize> = (0..used.len()).filter(|k| !bad.contains(k)).collect();
            let poses: Vec<Pose> = keep.iter().map(|&k| fit.poses[k]).collect();
            used = keep.iter().map(|&k| used[k]).collect();
            let first_pass = fit.iterations;
            fit = run_lm(&used, fit.cam, poses, &t, flags.max_iterations)?;
            fit.iterations += first_pass;
        }
    }
    rejected.sort_by_key(|r| r.index);
    calibration_of(fit, &used, &t, rejected)
}

/// The number of distortion coefficients of `model`, or Err naming the setting that cannot be
/// used (an empty image, fewer than 4 points per view, a fixed coefficient the model lacks, an
/// initial guess of another lens model).
fn checked_settings(
    (w, h): (u32, u32),
    model: LensModel,
    flags: &CalibrationFlags,
) -> Result<usize> {
    if w == 0 || h == 0 {
        return Err(invalid("image_size", format!("{w}×{h} must be non-zero")));
    }
    if flags.min_points_per_view < 4 {
        return Err(invalid(
            "min_points_per_view",
            "must be at least 4 (homography)",
        ));
    }
    let n_dist = match model {
        LensModel::BrownConrady => 5,
        LensModel::Fisheye => 4,
    };
    if let Some(&bad) = flags.fixed_distortion.iter().find(|&&d| d >= n_dist) {
        return Err(invalid(
            "fixed_distortion",
            format!("index {bad} ≥ {n_dist} coefficients"),
        ));
    }
    if let Some(g) = &flags.initial_guess {
        let ok = matches!(
            (g.distortion, model),
            (Distortion::BrownConrady(_), LensModel::BrownConrady)
                | (Distortion::Fisheye(_), LensModel::Fisheye)
        );
        if !ok {
            return Err(invalid(
                "initial_guess",
                "lens model differs from the requested one",
            ));
        }
    }
    Ok(n_dist)
}

/// Each valid view with its homography (target plane → pixels); the others in `rejected` with
/// the reason.
fn view_homographies<'v>(
    views: &'v [View],
    flags: &CalibrationFlags,
    rejected: &mut Vec<RejectedView>,
) -> Vec<(usize, &'v View, Matrix3<f64>)> {
    let mut usable = Vec::new();
    for (i, v) in views.iter().enumerate() {
        if let Err(reason) = validate_view(v, flags.min_points_per_view) {
            rejected.push(RejectedView { index: i, reason });
            continue;
        }
        let xy: Vec<[f64; 2]> = v.object_points.iter().map(|p| [p[0], p[1]]).collect();
        match homography_dlt(&xy, &v.image_points) {
            Ok(hm) => usable.push((i, v, hm)),
            Err(e) => rejected.push(RejectedView {
                index: i,
                reason: RejectionReason::DegenerateHomography(e.to_string()),
            }),
        }
    }
    usable
}

/// The initial camera: the flags' guess, or Zhang's closed form from the homographies (the
/// focal lengths alone about the image centre when that fails or the principal point is fixed),
/// without distortion.
fn initial_camera(
    hs: &[Matrix3<f64>],
    w: u32,
    h: u32,
    model: LensModel,
    flags: &CalibrationFlags,
) -> Result<CameraModel> {
    let zero = match model {
        LensModel::BrownConrady => Distortion::BrownConrady([0.0; 5]),
        LensModel::Fisheye => Distortion::Fisheye([0.0; 4]),
    };
    let centre = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    Ok(match &flags.initial_guess {
        Some(g) => *g,
        None => {
            let closed = if flags.fix_principal_point {
                None
            } else {
                intrinsics_from_homographies(hs, w, h).ok()
            };
            let [fx, fy, cx, cy] = match closed {
                Some(k) => k,
                None => {
                    let [fx, fy] = focal_from_homographies(hs, centre.0, centre.1)?;
                    [fx, fy, centre.0, centre.1]
                }
            };
            let (fx, fy) = if flags.fix_aspect_ratio {
                let f = (fx + fy) / 2.0;
                (f, f)
            } else {
                (fx, fy)
            };
            CameraModel::new(w, h, fx, fy, cx, cy, zero)?
        }
    })
}

/// The views (indices into `used`) whose RMS exceeds `kratio` × the median and the flags'
/// floor, each added to `rejected` with its figures — unless every view would be.
fn outlier_views(
    fit: &Fit,
    used: &[(usize, &View)],
    kratio: f64,
    flags: &CalibrationFlags,
    rejected: &mut Vec<RejectedView>,
) -> Vec<usize> {
    let rms = view_rms(&fit.residuals, used);
    let mut sorted = rms.clone();
    sorted.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    let median = if sorted.len() % 2 == 1 {
        sorted[sorted.len() / 2]
    } else {
        0.5 * (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2])
    };
    let bad: Vec<usize> = (0..used.len())
        .filter(|&k| rms[k] > kratio * median && rms[k] > flags.outlier_view_min_rms_px)
        .collect();
    if !bad.is_empty() && bad.len() < used.len() {
        for &b in &bad {
            rejected.push(RejectedView {
                index: used[b].0,
                reason: RejectionReason::OutlierRms {
                    rms_px: rms[b],
                    median_rms_px: median,
                    ratio_limit: kratio,
                },
            });
        }
    }
    bad
}

/// The calibration from the final fit: the intrinsics' covariance scaled by the residuals' σ²,
/// each view's pose, σ and RMS; Err when the points do not outnumber the free parameters or
/// JᵀJ is singular.
fn calibration_of(
    fit: Fit,
    used: &[(usize, &View)],
    t: &DMatrix<f64>,
    rejected: Vec<RejectedView>,
) -> Result<Calibration> {
    let n_points: usize = used.iter().map(|(_, v)| v.object_points.len()).sum();
    let p = t.ncols() + 6 * used.len();
    if 2 * n_points <= p {
        return Err(CameraError::TooFewPoints {
            what: "calibration (observations vs free parameters)".into(),
            needed: p / 2 + 1,
            got: n_points,
        });
    }
    let ss = fit.residuals.norm_squared();
    let sigma2 = ss / (2 * n_points - p) as f64;
    let inv = fit.normal_inverse.ok_or_else(|| CameraError::Degenerate {
        what: "calibration".into(),
        reason: "parameters not observable (JᵀJ singular): add views with more tilt".into(),
    })?;
    let cov = &inv * sigma2;
    let ni = t.ncols();
    let cov_intr = t * cov.view((0, 0), (ni, ni)) * t.transpose();
    let param_std: Vec<f64> = (0..cov_intr.nrows())
        .map(|i| cov_intr[(i, i)].max(0.0).sqrt())
        .collect();
    let rms_views = view_rms(&fit.residuals, used);
    let views_out = used
        .iter()
        .enumerate()
        .map(|(k, (i, v))| CalibratedView {
            index: *i,
            pose: fit.poses[k],
            pose_std: std::array::from_fn(|a| {
                cov[(ni + 6 * k + a, ni + 6 * k + a)].max(0.0).sqrt()
            }),
            rms_px: rms_views[k],
            n_points: v.object_points.len(),
        })
        .collect();
    Ok(Calibration {
        camera: fit.cam,
        param_std,
        param_covariance: cov_intr,
        views: views_out,
        rejected,
        rms_px: (ss / n_points as f64).sqrt(),
        sigma_px: sigma2.sqrt(),
        n_points,
        n_free_params: p,
        iterations: fit.iterations,
    })
}
