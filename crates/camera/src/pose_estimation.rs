//! Pose of a target from 2-D/3-D correspondences: IPPE for planar targets (Collins & Bartoli 2014,
//! both solutions), DLT for non-planar ones, Levenberg–Marquardt refinement of the reprojection
//! error in pixels, and the 6×6 pose covariance propagated from corner noise.
//!
//! The one implementation of a target's pose from its image points in the workspace: crates/vision's
//! marker poses and board poses both come from here.
//!
//! Covariance: Σ = (JᵀJ)⁻¹·σ_px², J = ∂(pixels)/∂δ with δ = (x, y, z, rot_x, rot_y, rot_z) in the
//! perturbation convention of [`crate::pose`] (translation and left-multiplied small rotation, both in
//! the camera = parent frame). Translation first is the workspace's one order for pose covariances
//! (also crates/kinematics' rigid registration): it is the order of
//! geometry_msgs/PoseWithCovariance.covariance (row-major 6×6), so what is computed is published
//! without reordering. σ_px is the standard deviation of each corner coordinate (pixels), assumed
//! independent; or, with [`estimate_planar_pose_weighted`], each point has its own 2×2 covariance
//! and Σ = (JᵀWJ)⁻¹, W the inverse point covariances. Camera intrinsics are treated as exact.

use crate::error::{CameraError, Result};
use crate::homography::homography_dlt;
use crate::model::CameraModel;
use crate::pose::Pose;
use crate::solver_bridge::{not_evaluable, solve_pixels};
use crate::undistort::{undistort_to_normalized, UndistortCriteria};
use metrocell_solver::{NotEvaluable, Problem};
use nalgebra::{DMatrix, Matrix2, Matrix3, Matrix6, Rotation3, Vector3};

/// A refined pose with its uncertainty.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseEstimate {
    /// Target → camera.
    pub pose: Pose,
    /// 6×6 covariance of (x, y, z, rot_x, rot_y, rot_z); units² of the target length unit and rad².
    pub covariance: Matrix6<f64>,
    /// Corner noise the covariance was propagated from (pixels); with per-point covariances, the
    /// RMS of their per-coordinate σ.
    pub sigma_px: f64,
    /// RMS reprojection distance sqrt(Σ‖r_i‖² / N) (pixels).
    pub rms_px: f64,
    /// For planar targets: the other IPPE solution after refinement and its RMS (pixels), to judge
    /// the flip ambiguity; None for non-planar targets.
    pub alternative: Option<(Pose, f64)>,
}

/// geometry_msgs/PoseWithCovariance content.
#[derive(Debug, Clone, PartialEq)]
pub struct RosPoseWithCovariance {
    pub position: [f64; 3],
    /// (x, y, z, w).
    pub orientation: [f64; 4],
    /// Row-major 6×6, order (x, y, z, rot_x, rot_y, rot_z), rotations about the parent frame's axes.
    pub covariance: [f64; 36],
}

impl PoseEstimate {
    pub fn to_ros(&self) -> RosPoseWithCovariance {
        let mut c = [0.0; 36];
        for i in 0..6 {
            for j in 0..6 {
                c[6 * i + j] = self.covariance[(i, j)];
            }
        }
        RosPoseWithCovariance {
            position: self.pose.tvec(),
            orientation: self.pose.quaternion_xyzw(),
            covariance: c,
        }
    }

    /// Standard uncertainties (x, y, z, rot_x, rot_y, rot_z).
    pub fn std_devs(&self) -> [f64; 6] {
        std::array::from_fn(|i| self.covariance[(i, i)].sqrt())
    }
}

fn check_inputs(object: &[[f64; 3]], image: &[[f64; 2]], needed: usize, what: &str) -> Result<()> {
    if object.len() != image.len() {
        return Err(CameraError::InvalidParameter {
            name: "points".into(),
            reason: format!(
                "{what}: {} object vs {} image points",
                object.len(),
                image.len()
            ),
        });
    }
    if object.len() < needed {
        return Err(CameraError::TooFewPoints {
            what: what.into(),
            needed,
            got: object.len(),
        });
    }
    for (i, (o, p)) in object.iter().zip(image).enumerate() {
        if o.iter().chain(p.iter()).any(|v| !v.is_finite()) {
            return Err(CameraError::BadPoint {
                index: i,
                reason: format!("{what}: non-finite coordinate"),
            });
        }
    }
    Ok(())
}

/// The two IPPE poses for points on the plane z = 0 of the target, from *ideal normalised* image
/// coordinates, ordered by RMS reprojection error in normalised units (best first).
pub fn ippe(object_xy: &[[f64; 2]], normalized: &[[f64; 2]]) -> Result<[Pose; 2]> {
    let n = object_xy.len();
    let (mx, my) = object_xy.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + p[0] / n as f64, a.1 + p[1] / n as f64)
    });
    let centred: Vec<[f64; 2]> = object_xy.iter().map(|p| [p[0] - mx, p[1] - my]).collect();
    let mut h = homography_dlt(&centred, normalized)?;
    h /= h[(2, 2)];
    // Jacobian of the homography at the (centred) origin and the image of the origin.
    let j00 = h[(0, 0)] - h[(2, 0)] * h[(0, 2)];
    let j01 = h[(0, 1)] - h[(2, 1)] * h[(0, 2)];
    let j10 = h[(1, 0)] - h[(2, 0)] * h[(1, 2)];
    let j11 = h[(1, 1)] - h[(2, 1)] * h[(1, 2)];
    let (p, q) = (h[(0, 2)], h[(1, 2)]);
    let (ra, rb) = ippe_rotations(j00, j01, j10, j11, p, q)?;
    let mut out = Vec::with_capacity(2);
    for r in [ra, rb] {
        let t = ippe_translation(&centred, normalized, &r);
        // Undo the centring: X_cam = R (X − m) + t.
        let t_full = t - r * Vector3::new(mx, my, 0.0);
        let pose = Pose {
            rotation: Rotation3::from_matrix_unchecked(r),
            translation: t_full,
        };
        let err: f64 = object_xy
            .iter()
            .zip(normalized)
            .map(|(o, m)| {
                let c = pose.transform(&Vector3::new(o[0], o[1], 0.0));
                (c.x / c.z - m[0]).powi(2) + (c.y / c.z - m[1]).powi(2)
            })
            .sum();
        out.push((pose, err));
    }
    out.sort_by(|a, b| a.1.partial_cmp(&b.1).unwrap_or(std::cmp::Ordering::Equal));
    Ok([out[0].0, out[1].0])
}

/// Rotation taking the unit vector along `a` onto +z (Collins' `rotateVec2ZAxis`).
fn rotate_vec_to_z(a: Vector3<f64>) -> Matrix3<f64> {
    let a = a.normalize();
    let c = a.z;
    if (1.0 + c).abs() < f32::EPSILON as f64 {
        return Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0);
    }
    let d = 1.0 / (1.0 + c);
    Matrix3::new(
        1.0 - a.x * a.x * d,
        -a.x * a.y * d,
        -a.x,
        -a.x * a.y * d,
        1.0 - a.y * a.y * d,
        -a.y,
        a.x,
        a.y,
        1.0 - (a.x * a.x + a.y * a.y) * d,
    )
}

/// IPPE's two rotations from the homography Jacobian J at the origin and its image (p, q).
fn ippe_rotations(
    j00: f64,
    j01: f64,
    j10: f64,
    j11: f64,
    p: f64,
    q: f64,
) -> Result<(Matrix3<f64>, Matrix3<f64>)> {
    let rv = rotate_vec_to_z(Vector3::new(p, q, 1.0)).transpose();
    let b00 = rv[(0, 0)] - p * rv[(2, 0)];
    let b01 = rv[(0, 1)] - p * rv[(2, 1)];
    let b10 = rv[(1, 0)] - q * rv[(2, 0)];
    let b11 = rv[(1, 1)] - q * rv[(2, 1)];
    let dtinv = 1.0 / (b00 * b11 - b01 * b10);
    let (bi00, bi01, bi10, bi11) = (dtinv * b11, -dtinv * b01, -dtinv * b10, dtinv * b00);
    let a00 = bi00 * j00 + bi01 * j10;
    let a01 = bi00 * j01 + bi01 * j11;
    let a10 = bi10 * j00 + bi11 * j10;
    let a11 = bi10 * j01 + bi11 * j11;
    let ata00 = a00 * a00 + a01 * a01;
    let ata01 = a00 * a10 + a01 * a11;
    let ata11 = a10 * a10 + a11 * a11;
    let gamma2 = 0.5 * (ata00 + ata11 + ((ata00 - ata11).powi(2) + 4.0 * ata01 * ata01).sqrt());
    let gamma = gamma2.sqrt();
    if !(gamma > f32::EPSILON as f64) || !gamma.is_finite() {
        return Err(CameraError::Degenerate {
            what: "IPPE".into(),
            reason: "homography Jacobian has zero scale".into(),
        });
    }
    let (r00, r01, r10, r11) = (a00 / gamma, a01 / gamma, a10 / gamma, a11 / gamma);
    let b0 = (1.0 - r00 * r00 - r10 * r10).max(0.0).sqrt();
    let mut b1 = (1.0 - r01 * r01 - r11 * r11).max(0.0).sqrt();
    if -r00 * r01 - r10 * r11 < 0.0 {
        b1 = -b1;
    }
    let det2 = r00 * r11 - r01 * r10;
    let m1 = Matrix3::new(
        r00,
        r01,
        b1 * r10 - b0 * r11,
        r10,
        r11,
        b0 * r01 - b1 * r00,
        b0,
        b1,
        det2,
    );
    let m2 = Matrix3::new(
        r00,
        r01,
        b0 * r11 - b1 * r10,
        r10,
        r11,
        b1 * r00 - b0 * r01,
        -b0,
        -b1,
        det2,
    );
    Ok((rv * m1, rv * m2))
}

/// Least-squares translation for a fixed rotation, linear in t (points on z = 0).
fn ippe_translation(
    object_xy: &[[f64; 2]],
    normalized: &[[f64; 2]],
    r: &Matrix3<f64>,
) -> Vector3<f64> {
    // Each point: x·(r3·X + tz) = r1·X + tx, y·(…) = r2·X + ty.
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    for (o, m) in object_xy.iter().zip(normalized) {
        let rx = r * Vector3::new(o[0], o[1], 0.0);
        let rows = [
            (Vector3::new(1.0, 0.0, -m[0]), m[0] * rx.z - rx.x),
            (Vector3::new(0.0, 1.0, -m[1]), m[1] * rx.z - rx.y),
        ];
        for (a, b) in rows {
            ata += a * a.transpose();
            atb += a * b;
        }
    }
    ata.try_inverse()
        .map(|i| i * atb)
        .unwrap_or_else(Vector3::zeros)
}

/// The reprojection errors in pixels, or whitened by Lᵢ⁻¹ (LᵢLᵢᵀ = Σᵢ, the point's covariance)
/// when `whiten` is given, so that the solver's plain least squares is the covariance-weighted one.
struct PoseProblem<'a> {
    cam: &'a CameraModel,
    object: Vec<Vector3<f64>>,
    image: &'a [[f64; 2]],
    whiten: Option<&'a [Matrix2<f64>]>,
}

impl PoseProblem<'_> {
    fn weighted(&self, i: usize, e: nalgebra::Vector2<f64>) -> nalgebra::Vector2<f64> {
        self.whiten.map_or(e, |w| w[i] * e)
    }
}

/// State: the pose as (t, rvec); steps: the perturbation δ of [`crate::pose`].
impl Problem for PoseProblem<'_> {
    fn residual_count(&self) -> usize {
        2 * self.object.len()
    }
    fn parameter_count(&self) -> usize {
        6
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> std::result::Result<(), NotEvaluable> {
        let pose = Pose::from_state(x);
        for (i, (p, m)) in self.object.iter().zip(self.image).enumerate() {
            let [u, v] = self.cam.project(&pose, p).map_err(not_evaluable)?;
            let e = self.weighted(i, nalgebra::Vector2::new(u - m[0], v - m[1]));
            r[2 * i] = e.x;
            r[2 * i + 1] = e.y;
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> std::result::Result<(), NotEvaluable> {
        let pose = Pose::from_state(x);
        for (i, (p, m)) in self.object.iter().zip(self.image).enumerate() {
            let pr = self
                .cam
                .project_with_jacobians(&pose, p)
                .map_err(not_evaluable)?;
            let e = self.weighted(i, nalgebra::Vector2::new(pr.u - m[0], pr.v - m[1]));
            r[2 * i] = e.x;
            r[2 * i + 1] = e.y;
            match self.whiten {
                None => j.view_mut((2 * i, 0), (2, 6)).copy_from(&pr.d_pose),
                Some(w) => j
                    .view_mut((2 * i, 0), (2, 6))
                    .copy_from(&(w[i] * pr.d_pose)),
            }
        }
        Ok(())
    }
    fn retract(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&Pose::from_state(x).perturbed(delta).to_state());
    }
}

/// Refines `initial` by LM on the pixel reprojection error; returns the pose, the RMS (px) and
/// (JᵀJ)⁻¹ (per unit pixel variance).
pub fn refine_pose(
    cam: &CameraModel,
    object: &[[f64; 3]],
    image: &[[f64; 2]],
    initial: Pose,
) -> Result<(Pose, f64, Matrix6<f64>)> {
    refine(cam, object, image, None, initial)
}

/// [`refine_pose`], the residuals whitened by `whiten` (Lᵢ⁻¹ per point) when given: then the
/// matrix returned is (JᵀWJ)⁻¹, the covariance itself. The RMS is in pixels either way.
fn refine(
    cam: &CameraModel,
    object: &[[f64; 3]],
    image: &[[f64; 2]],
    whiten: Option<&[Matrix2<f64>]>,
    initial: Pose,
) -> Result<(Pose, f64, Matrix6<f64>)> {
    check_inputs(object, image, 3, "pose refinement")?;
    let problem = PoseProblem {
        cam,
        object: object.iter().map(|p| Vector3::from(*p)).collect(),
        image,
        whiten,
    };
    let out = solve_pixels(&problem, &initial.to_state(), 100, "pose refinement")?;
    let pose = Pose::from_state(&out.x);
    let square_sum = match whiten {
        None => out.residuals.iter().map(|v| v * v).sum::<f64>(),
        Some(_) => problem
            .object
            .iter()
            .zip(image)
            .map(|(p, m)| {
                cam.project(&pose, p)
                    .map_or(f64::NAN, |[u, v]| (u - m[0]).powi(2) + (v - m[1]).powi(2))
            })
            .sum(),
    };
    let rms = (square_sum / object.len() as f64).sqrt();
    let inv = out
        .covariance_unscaled
        .ok_or_else(|| CameraError::Degenerate {
            what: "pose refinement".into(),
            reason: "pose not observable (JᵀJ singular)".into(),
        })?;
    Ok((pose, rms, Matrix6::from_iterator(inv.iter().copied())))
}

fn check_sigma(sigma_px: f64) -> Result<()> {
    if !(sigma_px.is_finite() && sigma_px > 0.0) {
        return Err(crate::error::invalid(
            "sigma_px",
            format!("{sigma_px} must be positive and finite"),
        ));
    }
    Ok(())
}

fn normalize_all(cam: &CameraModel, image: &[[f64; 2]]) -> Result<Vec<[f64; 2]>> {
    image
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = undistort_to_normalized(cam, *p, UndistortCriteria::CONVERGED);
            if n[0] <= -1e6 + 1.0 {
                Err(CameraError::BadPoint {
                    index: i,
                    reason: "cannot be undistorted (outside the lens model's range)".into(),
                })
            } else {
                Ok(n)
            }
        })
        .collect()
}

/// Pose of a planar target whose points lie on its z = 0 plane (|z| ≤ 1e-9 · extent): IPPE on
/// undistorted points, both solutions refined by LM, the lower reprojection error wins.
pub fn estimate_planar_pose(
    cam: &CameraModel,
    object: &[[f64; 3]],
    image: &[[f64; 2]],
    sigma_px: f64,
) -> Result<PoseEstimate> {
    check_inputs(object, image, 4, "planar pose")?;
    check_sigma(sigma_px)?;
    let ((pose, rms, inv), alternative) = planar_pose(cam, object, image, None)?;
    Ok(PoseEstimate {
        pose,
        covariance: inv * sigma_px * sigma_px,
        sigma_px,
        rms_px: rms,
        alternative,
    })
}

/// [`estimate_planar_pose`] with a 2×2 covariance (px²) for each image point, each positive
/// definite: the refinement weights each point by its inverse and the covariance is (JᵀWJ)⁻¹.
pub fn estimate_planar_pose_weighted(
    cam: &CameraModel,
    object: &[[f64; 3]],
    image: &[[f64; 2]],
    covariances: &[Matrix2<f64>],
) -> Result<PoseEstimate> {
    check_inputs(object, image, 4, "planar pose")?;
    if covariances.len() != image.len() {
        return Err(CameraError::InvalidParameter {
            name: "covariances".into(),
            reason: format!(
                "{} point covariances for {} image points",
                covariances.len(),
                image.len()
            ),
        });
    }
    let whiten = covariances
        .iter()
        .enumerate()
        .map(|(i, c)| {
            c.iter()
                .all(|v| v.is_finite())
                .then(|| c.cholesky().and_then(|ch| ch.l().try_inverse()))
                .flatten()
                .ok_or_else(|| CameraError::BadPoint {
                    index: i,
                    reason: "its covariance is not finite and positive definite".into(),
                })
        })
        .collect::<Result<Vec<_>>>()?;
    let ((pose, rms, covariance), alternative) = planar_pose(cam, object, image, Some(&whiten))?;
    let mean_variance =
        covariances.iter().map(|c| c.trace() / 2.0).sum::<f64>() / covariances.len() as f64;
    Ok(PoseEstimate {
        pose,
        covariance,
        sigma_px: mean_variance.sqrt(),
        rms_px: rms,
        alternative,
    })
}

/// The planar pose (pose, RMS px, inverse information) and the other IPPE solution with its RMS.
type PlanarSolutions = ((Pose, f64, Matrix6<f64>), Option<(Pose, f64)>);

fn planar_pose(
    cam: &CameraModel,
    object: &[[f64; 3]],
    image: &[[f64; 2]],
    whiten: Option<&[Matrix2<f64>]>,
) -> Result<PlanarSolutions> {
    let extent = object
        .iter()
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(0.0, f64::max);
    if let Some(i) = object
        .iter()
        .position(|p| p[2].abs() > 1e-9 * extent.max(1e-300))
    {
        return Err(CameraError::BadPoint {
            index: i,
            reason: "planar pose needs target points with z = 0".into(),
        });
    }
    let normalized = normalize_all(cam, image)?;
    let xy: Vec<[f64; 2]> = object.iter().map(|p| [p[0], p[1]]).collect();
    let candidates = ippe(&xy, &normalized)?;
    let mut refined = Vec::new();
    let mut last_err = None;
    for c in candidates {
        match refine(cam, object, image, whiten, c) {
            Ok(r) => refined.push(r),
            Err(e) => last_err = Some(e),
        }
    }
    if refined.is_empty() {
        return Err(last_err.unwrap_or(CameraError::NoConvergence {
            what: "planar pose".into(),
            reason: "no IPPE solution".into(),
        }));
    }
    refined.sort_by(|a, b| a.1.partial_cmp(&b.1).unwrap_or(std::cmp::Ordering::Equal));
    let alternative = refined.get(1).map(|r| (r.0, r.1));
    Ok((refined[0], alternative))
}

/// Pose from any ≥ 4 (planar) or ≥ 6 (non-planar) correspondences. Coplanar points (smallest
/// principal extent < 1e-6 of the largest) go through IPPE in the plane's own frame; otherwise a
/// normalised DLT on undistorted points seeds the LM refinement.
pub fn estimate_pose(
    cam: &CameraModel,
    object: &[[f64; 3]],
    image: &[[f64; 2]],
    sigma_px: f64,
) -> Result<PoseEstimate> {
    check_inputs(object, image, 4, "pose")?;
    check_sigma(sigma_px)?;
    let n = object.len() as f64;
    let c = object
        .iter()
        .fold(Vector3::zeros(), |a, p| a + Vector3::from(*p) / n);
    let mut cov = Matrix3::zeros();
    for p in object {
        let d = Vector3::from(*p) - c;
        cov += d * d.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| {
        eig.eigenvalues[b]
            .partial_cmp(&eig.eigenvalues[a])
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let (l0, l2) = (eig.eigenvalues[idx[0]], eig.eigenvalues[idx[2]].max(0.0));
    if !(l0 > 0.0) {
        return Err(CameraError::Degenerate {
            what: "pose".into(),
            reason: "all object points coincide".into(),
        });
    }
    if (l2 / l0).sqrt() < 1e-6 {
        // Plane frame: columns e1, e2, n (right-handed); plane coordinates X_p = Mᵀ(X − c).
        let e1 = eig.eigenvectors.column(idx[0]).into_owned();
        let e2 = eig.eigenvectors.column(idx[1]).into_owned();
        let m = Matrix3::from_columns(&[e1, e2, e1.cross(&e2)]);
        let local: Vec<[f64; 3]> = object
            .iter()
            .map(|p| {
                let q = m.transpose() * (Vector3::from(*p) - c);
                [q.x, q.y, 0.0]
            })
            .collect();
        let mut est = estimate_planar_pose(cam, &local, image, sigma_px)?;
        let to_target = |p: Pose| Pose {
            rotation: Rotation3::from_matrix_unchecked(p.rotation.matrix() * m.transpose()),
            translation: p.translation - p.rotation.matrix() * m.transpose() * c,
        };
        est.pose = to_target(est.pose);
        est.alternative = est.alternative.map(|(p, r)| (to_target(p), r));
        // The perturbation is in the camera frame, so the covariance is unchanged by the target-frame change.
        return Ok(est);
    }
    check_inputs(object, image, 6, "non-planar pose (DLT)")?;
    let normalized = normalize_all(cam, image)?;
    let init = dlt_pose(object, &normalized)?;
    let (pose, rms, inv) = refine_pose(cam, object, image, init)?;
    Ok(PoseEstimate {
        pose,
        covariance: inv * sigma_px * sigma_px,
        sigma_px,
        rms_px: rms,
        alternative: None,
    })
}

/// Normalised DLT for a 3×4 projection on ideal normalised points, projected onto SE(3).
fn dlt_pose(object: &[[f64; 3]], normalized: &[[f64; 2]]) -> Result<Pose> {
    let n = object.len();
    let c = object
        .iter()
        .fold(Vector3::zeros(), |a, p| a + Vector3::from(*p) / n as f64);
    let s = object
        .iter()
        .map(|p| (Vector3::from(*p) - c).norm())
        .sum::<f64>()
        / n as f64
        / 3f64.sqrt();
    let mut a = DMatrix::<f64>::zeros(2 * n, 12);
    for i in 0..n {
        let x = (Vector3::from(object[i]) - c) / s;
        let xh = [x.x, x.y, x.z, 1.0];
        let (u, v) = (normalized[i][0], normalized[i][1]);
        for k in 0..4 {
            a[(2 * i, k)] = xh[k];
            a[(2 * i, 8 + k)] = -u * xh[k];
            a[(2 * i + 1, 4 + k)] = xh[k];
            a[(2 * i + 1, 8 + k)] = -v * xh[k];
        }
    }
    let eig = nalgebra::SymmetricEigen::new(a.transpose() * &a);
    let imin = eig.eigenvalues.imin();
    let pv = eig.eigenvectors.column(imin);
    let m = Matrix3::new(
        pv[0], pv[1], pv[2], pv[4], pv[5], pv[6], pv[8], pv[9], pv[10],
    );
    let p4 = Vector3::new(pv[3], pv[7], pv[11]);
    let svd = m.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut scale = svd.singular_values.mean();
    let mut r = u * vt;
    if r.determinant() < 0.0 {
        r = -r;
        scale = -scale;
    }
    if !(scale.abs() > 0.0) {
        return Err(CameraError::Degenerate {
            what: "DLT pose".into(),
            reason: "zero projection matrix".into(),
        });
    }
    // M = λR, p4 = λ·t' with X' = (X − c)/s; the det(R) = +1 choice above fixes λ's sign.
    let t_norm = p4 / scale;
    let pose = Pose {
        rotation: Rotation3::from_matrix_unchecked(r),
        translation: t_norm * s - r * c,
    };
    if object
        .iter()
        .filter(|p| pose.transform(&Vector3::from(**p)).z > 0.0)
        .count()
        * 2
        < n
    {
        return Err(CameraError::Degenerate {
            what: "DLT pose".into(),
            reason: "most points end up behind the camera".into(),
        });
    }
    Ok(pose)
}
