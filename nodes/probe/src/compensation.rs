//! Touch-probe compensation.
//!
//! Conventions: machine frame, metres. The stylus-ball centre at the trigger is
//! c = (x, y, z) axis readings + `stylus_offset`. u is the unit approach direction (travel towards
//! the surface). The probe triggers pt(u) after contact (physics term `probe_pretravel`, probe
//! frame assumed parallel to the machine frame, stylus along z), so the centre at contact is
//! c − pt(u)·u, and the surface point lies one ball radius further along u:
//!   s = c − pt(u)·u + r·u.
//! Covariance: Σ_s = Σ_axes + (σ_r² + σ_pt²)·u·uᵀ, with σ_pt² = J Σ_p Jᵀ projected on u from the
//! pretravel parameters' covariance (diagonal, from their stated standard uncertainties).

use metrocell_physics::instrument::probe_pretravel::ProbePretravel;
use metrocell_physics::{PhysicsTerm, Signals};
use nalgebra::{Matrix3, Vector3};
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ProbeError {
    #[error("approach direction {0:?} has no length (no velocity at the trigger and none given)")]
    NoDirection([f64; 3]),
    #[error("trigger event: axis `{0}` missing (names: {1:?})")]
    MissingAxis(String, Vec<String>),
    #[error("trigger event: axis `{axis}` position {value} is not finite")]
    NonFinite { axis: String, value: f64 },
    #[error("pretravel model: {0}")]
    Physics(String),
}

/// The probe's calibrated constants.
#[derive(Debug, Clone)]
pub struct ProbeModel {
    /// Effective ball radius r [m] and its standard uncertainty.
    pub stylus_radius: f64,
    pub stylus_radius_std: f64,
    /// Offset from the axis readings to the ball centre [m].
    pub stylus_offset: Vector3<f64>,
    /// probe_pretravel parameters (p₀, a, b, p_z) [m], their standard uncertainties, lobe count.
    pub pretravel: [f64; 4],
    pub pretravel_std: [f64; 4],
    pub lobes: usize,
    /// Standard uncertainty of each axis reading [m] (independent).
    pub axis_std: f64,
}

/// A compensated hit.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensatedHit {
    pub stylus_centre: Vector3<f64>,
    pub approach: Vector3<f64>,
    pub pretravel: f64,
    pub surface_point: Vector3<f64>,
    pub covariance: Matrix3<f64>,
}

/// Unit approach direction from the axis velocities at the trigger, or `fallback` if they are zero.
pub fn approach_direction(
    velocity: Option<Vector3<f64>>,
    fallback: Vector3<f64>,
) -> Result<Vector3<f64>, ProbeError> {
    let v = velocity
        .filter(|v| v.norm() > 1e-12 && v.iter().all(|c| c.is_finite()))
        .unwrap_or(fallback);
    if v.norm() <= 1e-12 || !v.norm().is_finite() {
        return Err(ProbeError::NoDirection([v.x, v.y, v.z]));
    }
    Ok(v.normalize())
}

/// Compensate one trigger at axis readings `axes` (x, y, z) with approach direction `u` (unit).
pub fn compensate(
    model: &ProbeModel,
    axes: Vector3<f64>,
    u: Vector3<f64>,
) -> Result<CompensatedHit, ProbeError> {
    let term = ProbePretravel::new(model.lobes);
    let signals = Signals {
        probe_direction: Some(u),
        ..Default::default()
    };
    let d = term
        .predict(&model.pretravel, &signals)
        .map_err(|e| ProbeError::Physics(e.to_string()))?;
    let j = term
        .jacobian(&model.pretravel, &signals)
        .map_err(|e| ProbeError::Physics(e.to_string()))?;
    let disp = Vector3::new(d.value[0], d.value[1], d.value[2]);
    let pretravel = disp.dot(&u);
    let centre = axes + model.stylus_offset;
    let surface = centre - disp + model.stylus_radius * u;
    // Variance of pt along u from the parameters (J columns are u·∂pt/∂p_k).
    let var_pt: f64 = (0..4)
        .map(|k| (j.column(k).dot(&u) * model.pretravel_std[k]).powi(2))
        .sum();
    let cov = Matrix3::identity() * model.axis_std.powi(2)
        + (model.stylus_radius_std.powi(2) + var_pt) * u * u.transpose();
    Ok(CompensatedHit {
        stylus_centre: centre,
        approach: u,
        pretravel,
        surface_point: surface,
        covariance: cov,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> ProbeModel {
        ProbeModel {
            stylus_radius: 1.5e-3,
            stylus_radius_std: 0.2e-6,
            stylus_offset: Vector3::new(0.0, 0.0, -0.05),
            pretravel: [10e-6, 3e-6, 0.0, 4e-6],
            pretravel_std: [0.5e-6, 0.5e-6, 0.5e-6, 0.5e-6],
            lobes: 3,
            axis_std: 1e-6,
        }
    }

    #[test]
    fn radius_and_pretravel_are_removed_along_the_approach() {
        // Approaching +x (φ = 0): pt = p₀ + a = 13 µm. Surface = centre − 13 µm x̂ + 1.5 mm x̂.
        let h = compensate(&model(), Vector3::new(0.1, 0.2, 0.3), Vector3::x()).unwrap();
        assert!((h.pretravel - 13e-6).abs() < 1e-12);
        let want = Vector3::new(0.1 - 13e-6 + 1.5e-3, 0.2, 0.25);
        assert!(
            (h.surface_point - want).norm() < 1e-12,
            "{:?}",
            h.surface_point
        );
        // Along x: axis² + r² + (p₀ and a parts)²; across: axis² only.
        let var_x = 1e-12 + 0.04e-12 + 2.0 * 0.25e-12;
        assert!(
            (h.covariance[(0, 0)] - var_x).abs() < 1e-18
                && (h.covariance[(1, 1)] - 1e-12).abs() < 1e-18
        );
        // Approaching −z (down onto a plane): pt = p_z = 4 µm, surface below the centre by r − 4 µm.
        let h = compensate(&model(), Vector3::new(0.0, 0.0, 0.1), -Vector3::z()).unwrap();
        assert!(
            (h.surface_point.z - (0.05 + 4e-6 - 1.5e-3)).abs() < 1e-12,
            "{}",
            h.surface_point.z
        );
        // φ = 60° (3 lobes): cos(3φ) = −1 → pt = p₀ − a = 7 µm.
        let u = Vector3::new(0.5, 3f64.sqrt() / 2.0, 0.0);
        assert!(
            (compensate(&model(), Vector3::zeros(), u).unwrap().pretravel - 7e-6).abs() < 1e-12
        );
    }

    #[test]
    fn direction_from_velocity_or_fallback() {
        let u = approach_direction(Some(Vector3::new(0.0, -0.02, 0.0)), Vector3::z()).unwrap();
        assert_eq!(u, -Vector3::y());
        assert_eq!(
            approach_direction(Some(Vector3::zeros()), -Vector3::z()).unwrap(),
            -Vector3::z()
        );
        assert!(approach_direction(None, Vector3::zeros()).is_err());
    }
}
