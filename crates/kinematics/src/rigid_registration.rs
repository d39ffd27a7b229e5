//! Rigid registration: the closed-form (weighted) Kabsch rotation, and the pose of one frame in
//! another from point correspondences with full covariances. The one implementation in the
//! workspace: the laser tracker's registration (crates/tracker re-exports it), the instrument pose
//! of crates/estimation and the camera-to-tool alignment of [`crate::frame_alignment`] use it.
//!
//! Convention (stated once, used everywhere): the pose (R, t) maps source (instrument)
//! coordinates to target (machine) coordinates, q = R·p + t; for the tracker it is the transform
//! of the `tf` child frame `tracker` in the parent frame `machine`. Its covariance is 6×6 in the
//! order (δt_x, δt_y, δt_z, δθ_x, δθ_y, δθ_z) — translation first, the order of
//! geometry_msgs/PoseWithCovariance and of crates/camera's pose covariance, so that every pose
//! covariance in the workspace is written and published without reordering: δt the translation
//! (m), δθ a small rotation vector (rad) about the target frame's axes, applied on the left
//! (R' = exp([δθ]×)·R).
//!
//! Method: weighted Kabsch (closed form, scalar weights 3/trace Σ) for the start, then the
//! workspace's Levenberg–Marquardt (metrocell_solver) on Σ rᵢᵀ Wᵢ rᵢ with the full
//! Wᵢ = (R Σpᵢ Rᵀ + Σqᵢ)⁻¹, rᵢ = R pᵢ + t − qᵢ, reweighted until R settles (see [`register`]).
//! The covariance is the inverse information at the optimum, scaled by the reduced χ² when the
//! residuals exceed their covariances (the nominal points are then not where the machine
//! really is; never scaled down: the points' covariances are stated, not estimated).

use crate::error::KinematicsError;
use metrocell_solver::{solve, NotEvaluable, Options, Problem};
use nalgebra::{DMatrix, Matrix3, Matrix6, Rotation3, UnitQuaternion, Vector3};

/// One correspondence: a tracker point and its nominal machine point, with covariances (m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correspondence {
    pub tracker: Vector3<f64>,
    pub tracker_covariance: Matrix3<f64>,
    pub machine: Vector3<f64>,
    pub machine_covariance: Matrix3<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Registration {
    pub rotation: Rotation3<f64>,
    /// m
    pub translation: Vector3<f64>,
    /// order (δt, δθ), translation first, see the module doc
    pub covariance: Matrix6<f64>,
    /// Σ rᵀ W r at the optimum
    pub chi2: f64,
    /// 3n − 6
    pub dof: usize,
    /// root mean square residual length, m
    pub rms: f64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegistrationError {
    #[error("registration needs at least 3 points, has {0}")]
    TooFew(usize),
    #[error("correspondence {0} has a non-finite coordinate or covariance")]
    NotFinite(usize),
    #[error(
        "the points are collinear (or coincide): the rotation about their line is not determined"
    )]
    Degenerate,
}

impl Registration {
    /// Machine point and covariance of a tracker point, including the pose's uncertainty.
    pub fn to_machine(&self, p: &Vector3<f64>, cov: &Matrix3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        let rp = self.rotation * p;
        let j = pose_jacobian(&rp);
        let r = self.rotation.matrix();
        (
            rp + self.translation,
            r * cov * r.transpose() + j * self.covariance * j.transpose(),
        )
    }
}

/// ∂(R p + t)/∂(δt, δθ) at R p = `rp`.
fn pose_jacobian(rp: &Vector3<f64>) -> nalgebra::Matrix3x6<f64> {
    let mut j = nalgebra::Matrix3x6::zeros();
    j.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    j.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-rp.cross_matrix()));
    j
}

/// Reweightings at most. Each turns R about a millionth as far as the one before (µrad from
/// Kabsch's start, then pico-radians), so two suffice in the tests.
const MAX_REWEIGHTINGS: usize = 10;

/// The reweighting stops after a solve that turned R by less than this (rad): the next would
/// turn it by orders of magnitude less than round-off at 1 m.
const SETTLED_ROTATION: f64 = 1e-10;

/// The tracker pose from ≥ 3 non-collinear correspondences.
///
/// Wᵢ depends on R, which a [`Problem`] (residuals whitened by a fixed factor each) cannot carry
/// exactly; so the weights are frozen at the current R, the shared solver minimises Σ rᵢᵀ Wᵢ rᵢ
/// with them, and this repeats until R settles (iteratively reweighted least squares). Its fixed
/// point is the one of Gauss–Newton with Wᵢ re-evaluated at every step: Σ Jᵢᵀ Wᵢ(R) rᵢ = 0.
pub fn register(points: &[Correspondence]) -> Result<Registration, RegistrationError> {
    if points.len() < 3 {
        return Err(RegistrationError::TooFew(points.len()));
    }
    for (i, c) in points.iter().enumerate() {
        let finite = c
            .tracker
            .iter()
            .chain(c.machine.iter())
            .chain(c.tracker_covariance.iter())
            .chain(c.machine_covariance.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(RegistrationError::NotFinite(i));
        }
    }
    let (mut rotation, mut translation) = weighted_kabsch_start(points)?;
    // Every solve starts within the noise of its optimum (Kabsch's, then the previous pass's),
    // where the problem is linear to round-off: so the first step is left nearly undamped. With
    // relative tolerances 1e-10 noise-free points come out exact to 1e-15 m, and noisy ones
    // within 2e-10 m and rad of a Gauss–Newton run to round-off.
    let options = Options {
        initial_damping: 1e-8,
        ftol: 1e-10,
        xtol: 1e-10,
        gtol: 1e-10,
        ..Options::default()
    };
    let mut weights = FrozenWeights::at(points, rotation)?;
    let mut info_inverse = None;
    for _ in 0..MAX_REWEIGHTINGS {
        let t = translation;
        let fit = solve(&weights, &[0.0, 0.0, 0.0, t.x, t.y, t.z], &options)
            .map_err(|_| RegistrationError::Degenerate)?;
        (rotation, translation) = weights.pose(&fit.x);
        info_inverse = fit.covariance_unscaled;
        weights = FrozenWeights::at(points, rotation)?;
        let turned = Vector3::new(fit.x[0], fit.x[1], fit.x[2]).norm();
        if turned < SETTLED_ROTATION {
            break;
        }
    }
    let info_inverse = info_inverse.ok_or(RegistrationError::Degenerate)?;
    let mut chi2 = 0.0;
    let mut ss = 0.0;
    for (c, whiten) in points.iter().zip(&weights.whiten) {
        let r = rotation * c.tracker + translation - c.machine;
        chi2 += (whiten * r).norm_squared();
        ss += r.norm_squared();
    }
    let dof = 3 * points.len() - 6;
    let birge = if dof > 0 {
        (chi2 / dof as f64).max(1.0)
    } else {
        1.0
    };
    // the solver's state is (δθ, δt); the covariance is published translation first
    let state_order = Matrix6::from_iterator(info_inverse.iter().copied());
    let covariance = Matrix6::from_fn(|i, j| state_order[((i + 3) % 6, (j + 3) % 6)]) * birge;
    Ok(Registration {
        rotation,
        translation,
        covariance,
        chi2,
        dof,
        rms: (ss / points.len() as f64).sqrt(),
    })
}

/// The residuals Lᵢ⁻¹·rᵢ with LᵢLᵢᵀ = R₀ Σpᵢ R₀ᵀ + Σqᵢ = Wᵢ⁻¹ at a fixed R₀, so that the solver's
/// plain least squares is Σ rᵢᵀ Wᵢ rᵢ with the weights frozen there.
///
/// State x = (θ, t): θ the rotation vector of R·R₀⁻¹ (small, so never near the rotation vector's
/// singularity at π whatever the tracker's heading), t in m. A step δ = (δθ, δt) is the
/// perturbation of the module doc, so the solver's (J̃ᵀJ̃)⁻¹ is the covariance, rotation first
/// (permuted to the module's translation-first order by [`register`]).
struct FrozenWeights<'a> {
    points: &'a [Correspondence],
    rotation: Rotation3<f64>,
    whiten: Vec<Matrix3<f64>>,
}

impl<'a> FrozenWeights<'a> {
    /// The weights at `rotation`; Degenerate where R Σp Rᵀ + Σq is not positive definite.
    fn at(
        points: &'a [Correspondence],
        rotation: Rotation3<f64>,
    ) -> Result<Self, RegistrationError> {
        let r = rotation.matrix();
        let whiten = points
            .iter()
            .map(|c| {
                (r * c.tracker_covariance * r.transpose() + c.machine_covariance)
                    .cholesky()
                    .and_then(|ch| ch.l().try_inverse())
                    .ok_or(RegistrationError::Degenerate)
            })
            .collect::<Result<_, _>>()?;
        Ok(FrozenWeights {
            points,
            rotation,
            whiten,
        })
    }

    fn pose(&self, x: &[f64]) -> (Rotation3<f64>, Vector3<f64>) {
        (
            Rotation3::new(Vector3::new(x[0], x[1], x[2])) * self.rotation,
            Vector3::new(x[3], x[4], x[5]),
        )
    }
}

impl Problem for FrozenWeights<'_> {
    fn residual_count(&self) -> usize {
        3 * self.points.len()
    }
    fn parameter_count(&self) -> usize {
        6
    }
    fn residuals(&self, x: &[f64], out: &mut [f64]) -> Result<(), NotEvaluable> {
        let (rotation, translation) = self.pose(x);
        for (i, (c, whiten)) in self.points.iter().zip(&self.whiten).enumerate() {
            let r = whiten * (rotation * c.tracker + translation - c.machine);
            out[3 * i..3 * i + 3].copy_from_slice(r.as_slice());
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        out: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        let (rotation, translation) = self.pose(x);
        for (i, (c, whiten)) in self.points.iter().zip(&self.whiten).enumerate() {
            let rp = rotation * c.tracker;
            let r = whiten * (rp + translation - c.machine);
            out[3 * i..3 * i + 3].copy_from_slice(r.as_slice());
            // L⁻¹·pose_jacobian(Rp) = [−L⁻¹[Rp]×, L⁻¹], row k of −L⁻¹[Rp]× being (Rp × ℓₖ)ᵀ:
            // written out, as the 3×3·3×6 product took a quarter of the registration's time
            for k in 0..3 {
                let l = whiten.row(k).transpose();
                let d = rp.cross(&l);
                for m in 0..3 {
                    j[(3 * i + k, m)] = d[m];
                    j[(3 * i + k, 3 + m)] = l[m];
                }
            }
        }
        Ok(())
    }
    fn retract(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(delta[0], delta[1], delta[2]))
            * UnitQuaternion::from_scaled_axis(Vector3::new(x[0], x[1], x[2]));
        out[..3].copy_from_slice(q.scaled_axis().as_slice());
        for k in 3..6 {
            out[k] = x[k] + delta[k];
        }
    }
}

/// Closed-form weighted Kabsch start, weights 3/trace(Σpᵢ + Σqᵢ).
fn weighted_kabsch_start(
    points: &[Correspondence],
) -> Result<(Rotation3<f64>, Vector3<f64>), RegistrationError> {
    let w: Vec<f64> = points
        .iter()
        .map(|c| {
            3.0 / (c.tracker_covariance + c.machine_covariance)
                .trace()
                .max(f64::MIN_POSITIVE)
        })
        .collect();
    let source: Vec<Vector3<f64>> = points.iter().map(|c| c.tracker).collect();
    let target: Vec<Vector3<f64>> = points.iter().map(|c| c.machine).collect();
    let (r, t) =
        kabsch_rigid(&source, &target, Some(&w)).map_err(|_| RegistrationError::Degenerate)?;
    Ok((Rotation3::from_matrix_unchecked(r), t))
}

/// The rotation R minimising Σ wᵢ‖targetᵢ − R·sourceᵢ‖² (Kabsch, by the SVD of
/// H = Σ wᵢ targetᵢ sourceᵢᵀ = U S Vᵀ: R = U diag(1, 1, det(U Vᵀ)) Vᵀ, a proper rotation even
/// where the best orthogonal matrix would be a reflection). The vectors are taken as given:
/// directions or moves as they stand, points centred first ([`kabsch_rigid`]). `weights`: None
/// for equal weights.
///
/// Errors: lengths differ, fewer than two vectors, or they are collinear (or zero): then the
/// second singular value of H is below 1e-12 of the first and the rotation about their common
/// direction is not determined.
pub fn kabsch_rotation(
    source: &[Vector3<f64>],
    target: &[Vector3<f64>],
    weights: Option<&[f64]>,
) -> Result<Matrix3<f64>, KinematicsError> {
    if source.len() != target.len() {
        return Err(KinematicsError::LengthMismatch {
            field: "Kabsch target vectors".into(),
            got: target.len(),
            expected: source.len(),
        });
    }
    if let Some(w) = weights.filter(|w| w.len() != source.len()) {
        return Err(KinematicsError::LengthMismatch {
            field: "Kabsch weights".into(),
            got: w.len(),
            expected: source.len(),
        });
    }
    if source.len() < 2 {
        return Err(KinematicsError::Degenerate {
            reason: format!("Kabsch needs at least two vectors, has {}", source.len()),
        });
    }
    if let Some(i) = (0..source.len()).find(|&i| {
        !(source[i]
            .iter()
            .chain(target[i].iter())
            .all(|v| v.is_finite())
            && weights.is_none_or(|w| w[i].is_finite()))
    }) {
        return Err(KinematicsError::Degenerate {
            reason: format!("Kabsch: vector pair {i} has a non-finite coordinate or weight"),
        });
    }
    let h: Matrix3<f64> = (0..source.len())
        .map(|i| target[i] * source[i].transpose() * weights.map_or(1.0, |w| w[i]))
        .sum();
    let svd = h.svd(true, true);
    let (u, v_t) = match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => (u, v_t),
        _ => {
            return Err(KinematicsError::Degenerate {
                reason: "Kabsch: the SVD did not converge".into(),
            })
        }
    };
    let mut s = svd.singular_values;
    s.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
    // collinear vectors leave one rotation free: the second singular value vanishes (the test
    // is written so that NaN fails it)
    if !(s[1] > 1e-12 * s[0].max(f64::MIN_POSITIVE)) || s[0] == 0.0 {
        return Err(KinematicsError::Degenerate {
            reason: "the vectors are collinear (or zero): the rotation about their common \
                     direction is not determined"
                .into(),
        });
    }
    let d = (u * v_t).determinant().signum();
    Ok(u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t)
}

/// The rigid transform (R, t) minimising Σ wᵢ‖targetᵢ − (R·sourceᵢ + t)‖²: [`kabsch_rotation`]
/// of the points about their weighted centroids, t = q̄ − R·p̄.
pub fn kabsch_rigid(
    source: &[Vector3<f64>],
    target: &[Vector3<f64>],
    weights: Option<&[f64]>,
) -> Result<(Matrix3<f64>, Vector3<f64>), KinematicsError> {
    let w = |i: usize| weights.map_or(1.0, |w| w.get(i).copied().unwrap_or(f64::NAN));
    let sw: f64 = (0..source.len()).map(w).sum();
    let centroid = |v: &[Vector3<f64>]| {
        v.iter()
            .enumerate()
            .map(|(i, p)| p * w(i))
            .sum::<Vector3<f64>>()
            / sw
    };
    let (pc, qc) = (centroid(source), centroid(target));
    let ps: Vec<Vector3<f64>> = source.iter().map(|p| p - pc).collect();
    let qs: Vec<Vector3<f64>> = target.iter().map(|q| q - qc).collect();
    let r = kabsch_rotation(&ps, &qs, weights)?;
    Ok((r, qc - r * pc))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rotation() -> Matrix3<f64> {
        Rotation3::from_euler_angles(0.3, -1.1, 2.9).into_inner()
    }

    #[test]
    fn kabsch_rigid_recovers_a_weighted_pose_exactly() {
        let (r, t) = (rotation(), Vector3::new(0.4, -1.2, 0.7));
        let source = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 2.0, 0.0),
            Vector3::new(0.3, 0.5, 1.5),
        ];
        let target: Vec<Vector3<f64>> = source.iter().map(|p| r * p + t).collect();
        let (rf, tf) = kabsch_rigid(&source, &target, Some(&[1.0, 4.0, 0.5, 2.0])).unwrap();
        assert!((rf - r).norm() < 1e-14, "{rf}");
        assert!((tf - t).norm() < 1e-14, "{tf}");
        assert!((rf.determinant() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn kabsch_rotation_is_proper_for_planar_vectors_and_names_bad_input() {
        // two moves in a plane: the best orthogonal matrix may be a reflection, ours is not
        let r = rotation();
        let source = [Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0)];
        let target: Vec<Vector3<f64>> = source.iter().map(|v| r * v).collect();
        let rf = kabsch_rotation(&source, &target, None).unwrap();
        assert!((rf - r).norm() < 1e-14 && (rf.determinant() - 1.0).abs() < 1e-14);
        let v = Vector3::new(1.0, 2.0, 3.0);
        let collinear = kabsch_rotation(&[v, v * 3.0], &[v, v * 3.0], None).unwrap_err();
        assert!(collinear.to_string().contains("collinear"), "{collinear}");
        assert!(matches!(
            kabsch_rotation(&[v], &[v, v], None),
            Err(KinematicsError::LengthMismatch { .. })
        ));
        assert!(matches!(
            kabsch_rotation(&[v, v], &[v, v], Some(&[1.0])),
            Err(KinematicsError::LengthMismatch { .. })
        ));
        let nan = Vector3::new(f64::NAN, 0.0, 0.0);
        assert!(kabsch_rotation(&[v, nan], &[v, v], None).is_err());
    }
}
