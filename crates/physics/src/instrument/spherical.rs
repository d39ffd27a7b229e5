//! Laser-tracker spherical coordinates ↔ Cartesian, and the covariance that follows (the one
//! copy in the workspace; crates/compensation re-exports it for the nodes).
//!
//! Convention (tracker frame, stated once; the same as `metrocell_msgs/msg/TrackerMeasurement`):
//! right-handed, z up; ρ = |p|, azimuth θ = atan2(y, x) from +x towards +y, elevation
//! φ = atan2(z, √(x² + y²)) from the xy plane towards +z; p = ρ·(cos φ cos θ, cos φ sin θ, sin φ).

use nalgebra::{Matrix3, Vector3};

/// Cartesian → (ρ, azimuth, elevation).
pub fn to_spherical(p: &Vector3<f64>) -> (f64, f64, f64) {
    let rho = p.norm();
    (rho, p.y.atan2(p.x), p.z.atan2(p.x.hypot(p.y)))
}

/// (ρ, azimuth, elevation) → Cartesian.
pub fn from_spherical(rho: f64, az: f64, el: f64) -> Vector3<f64> {
    let (se, ce) = el.sin_cos();
    let (sa, ca) = az.sin_cos();
    Vector3::new(rho * ce * ca, rho * ce * sa, rho * se)
}

/// ∂p/∂(ρ, azimuth, elevation).
pub fn spherical_jacobian(rho: f64, az: f64, el: f64) -> Matrix3<f64> {
    let (se, ce) = el.sin_cos();
    let (sa, ca) = az.sin_cos();
    Matrix3::new(
        ce * ca,
        -rho * ce * sa,
        -rho * se * ca,
        ce * sa,
        rho * ce * ca,
        -rho * se * sa,
        se,
        0.0,
        rho * ce,
    )
}

/// Covariance of the Cartesian point for independent σ of range, azimuth and elevation.
pub fn point_covariance(
    rho: f64,
    az: f64,
    el: f64,
    sigma_range: f64,
    sigma_az: f64,
    sigma_el: f64,
) -> Matrix3<f64> {
    let j = spherical_jacobian(rho, az, el);
    let s = Matrix3::from_diagonal(&Vector3::new(
        sigma_range * sigma_range,
        sigma_az * sigma_az,
        sigma_el * sigma_el,
    ));
    j * s * j.transpose()
}

/// Standard uncertainties of one tracker reading.
///
/// Radial noise grows with range as `radial_base + radial_per_metre·r` (the a + b·L form
/// tracker makers specify); angular noise is one standard deviation per angle in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphericalNoise {
    /// m
    pub radial_base: f64,
    /// m/m
    pub radial_per_metre: f64,
    /// rad, azimuth and elevation alike
    pub angular: f64,
}

impl SphericalNoise {
    /// Standard deviation of the range at `range` metres.
    pub fn radial_sigma(&self, range: f64) -> f64 {
        self.radial_base + self.radial_per_metre * range
    }
}

/// Cartesian point and its 3×3 covariance (m²) from range (m), azimuth and elevation (rad).
///
/// First-order propagation Σ = J·diag(σr², σaz², σel²)·Jᵀ; at tracker ranges the angular noise
/// is micro-radians, so the linearisation error is far below the noise itself.
pub fn spherical_to_cartesian(
    range: f64,
    azimuth: f64,
    elevation: f64,
    noise: &SphericalNoise,
) -> (Vector3<f64>, Matrix3<f64>) {
    (
        from_spherical(range, azimuth, elevation),
        point_covariance(
            range,
            azimuth,
            elevation,
            noise.radial_sigma(range),
            noise.angular,
            noise.angular,
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn spherical_round_trip_and_jacobian() {
        let p = Vector3::new(1.2, -0.7, 0.4);
        let (r, a, e) = to_spherical(&p);
        assert!((from_spherical(r, a, e) - p).norm() < 1e-15);
        let j = spherical_jacobian(r, a, e);
        let h = 1e-7;
        for (k, (dr, da, de)) in [(h, 0.0, 0.0), (0.0, h, 0.0), (0.0, 0.0, h)]
            .into_iter()
            .enumerate()
        {
            let fd = (from_spherical(r + dr, a + da, e + de)
                - from_spherical(r - dr, a - da, e - de))
                / (2.0 * h);
            assert!((fd - j.column(k)).norm() < 1e-7, "column {k}");
        }
    }

    #[test]
    fn axes_of_the_convention() {
        let n = SphericalNoise {
            radial_base: 0.0,
            radial_per_metre: 0.0,
            angular: 0.0,
        };
        let (p, _) = spherical_to_cartesian(2.0, 0.0, 0.0, &n);
        assert!((p - Vector3::new(2.0, 0.0, 0.0)).norm() < 1e-15);
        let (p, _) = spherical_to_cartesian(2.0, std::f64::consts::FRAC_PI_2, 0.0, &n);
        assert!((p - Vector3::new(0.0, 2.0, 0.0)).norm() < 1e-15);
        let (p, _) = spherical_to_cartesian(2.0, 0.3, std::f64::consts::FRAC_PI_2, &n);
        assert!((p - Vector3::new(0.0, 0.0, 2.0)).norm() < 1e-15);
    }

    #[test]
    fn covariance_matches_monte_carlo() {
        use rand::Rng;
        let noise = SphericalNoise {
            radial_base: 10e-6,
            radial_per_metre: 5e-6,
            angular: 5e-6,
        };
        let (r, az, el) = (3.0, 0.7, 0.2);
        let (_, cov) = spherical_to_cartesian(r, az, el, &noise);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 40_000;
        let mut samples = Vec::with_capacity(n);
        let gauss = |rng: &mut ChaCha8Rng| -> f64 {
            // Box–Muller: rand 0.9 without rand_distr.
            let u1: f64 = rng.random::<f64>().max(1e-300);
            let u2: f64 = rng.random();
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        };
        for _ in 0..n {
            let rr = r + noise.radial_sigma(r) * gauss(&mut rng);
            let a = az + noise.angular * gauss(&mut rng);
            let e = el + noise.angular * gauss(&mut rng);
            let zero = SphericalNoise {
                radial_base: 0.0,
                radial_per_metre: 0.0,
                angular: 0.0,
            };
            samples.push(spherical_to_cartesian(rr, a, e, &zero).0);
        }
        let mean = samples.iter().sum::<Vector3<f64>>() / n as f64;
        let emp = samples
            .iter()
            .map(|s| (s - mean) * (s - mean).transpose())
            .sum::<Matrix3<f64>>()
            / (n as f64 - 1.0);
        for i in 0..3 {
            let rel = (emp[(i, i)] - cov[(i, i)]).abs() / cov[(i, i)];
            assert!(
                rel < 0.03,
                "variance {i}: empirical {} vs propagated {}",
                emp[(i, i)],
                cov[(i, i)]
            );
        }
    }
}
