//! Laser-tracker measurement model (pure functions plus the seeded beam-break process).
//!
//! Conventions (tracker frame, stated once): ρ = |p|, azimuth θ = atan2(y, x) about the
//! tracker's z axis from its x axis, elevation φ = atan2(z, √(x² + y²)) above the xy plane;
//! p = ρ·(cos φ cos θ, cos φ sin θ, sin φ).
//!
//! What the tracker reads for a target at true spherical (ρ, θ, φ):
//! * range: ρ_m = ρ + Δρ_refraction + Δρ_warmup + σ_eff·N(0,1), with
//!   Δρ_refraction = ρ·(n_true/n_station − 1) (the interferometer counts the true optical path
//!   and divides by the index from its own weather station: thesis P1 eq. 10, one section),
//!   Δρ_warmup = A + B(1 − e^(−t_on/τ)) (thesis eq. 3.1), and
//!   σ_eff = √((a + bρ)² + (cρ)²) (physics `turbulence`: c > 0 only inside turbulence windows);
//! * angles: θ_m = θ + σ_ang·N, φ_m = φ + σ_ang·N.
//!
//! The *stated* covariance of a sample is what the instrument believes: σ_ρ = a + b·ρ and σ_ang,
//! propagated through the spherical→Cartesian Jacobian. Turbulence is therefore visible as
//! scatter above the stated σ (flagged downstream, never fitted as bias).

use nalgebra::{Matrix3, Vector3};

use crate::noise::NoiseStream;

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
    Matrix3::new(ce * ca, -rho * ce * sa, -rho * se * ca, ce * sa, rho * ce * ca, -rho * se * sa, se, 0.0, rho * ce)
}

/// Covariance of the Cartesian point for independent σ of range, azimuth and elevation.
pub fn point_covariance(rho: f64, az: f64, el: f64, sigma_range: f64, sigma_az: f64, sigma_el: f64) -> Matrix3<f64> {
    let j = spherical_jacobian(rho, az, el);
    let s = Matrix3::from_diagonal(&Vector3::new(sigma_range * sigma_range, sigma_az * sigma_az, sigma_el * sigma_el));
    j * s * j.transpose()
}

/// Stated range σ, a + b·ρ.
pub fn stated_range_sigma(constant: f64, per_metre: f64, rho: f64) -> f64 {
    constant + per_metre * rho
}

/// Range error of one uniform section from refractivities N = n − 1 (no cancellation):
/// ρ·(n_true/n_station − 1) = ρ·(N_true − N_station)/(1 + N_station).
pub fn refraction_range_error(rho: f64, refractivity_true: f64, refractivity_station: f64) -> f64 {
    rho * (refractivity_true - refractivity_station) / (1.0 + refractivity_station)
}

/// Poisson beam breaks with exponential durations, queried at non-decreasing times.
#[derive(Debug, Clone)]
pub struct BeamBreakProcess {
    rng: NoiseStream,
    rate: f64,
    mean_duration: f64,
    start: f64,
    end: f64,
}

impl BeamBreakProcess {
    pub fn new(rng: NoiseStream, rate: f64, mean_duration: f64) -> Self {
        let mut p = Self { rng, rate, mean_duration, start: f64::INFINITY, end: f64::NEG_INFINITY };
        if rate > 0.0 {
            p.start = p.rng.exponential(1.0 / rate);
            p.end = p.start + p.rng.exponential(mean_duration);
        }
        p
    }

    /// Whether the beam is broken at t.
    pub fn broken(&mut self, t: f64) -> bool {
        while t >= self.end && self.rate > 0.0 {
            self.start = self.end + self.rng.exponential(1.0 / self.rate);
            self.end = self.start + self.rng.exponential(self.mean_duration);
        }
        t >= self.start && t < self.end
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spherical_round_trip_and_jacobian() {
        let p = Vector3::new(1.2, -0.7, 0.4);
        let (r, a, e) = to_spherical(&p);
        assert!((from_spherical(r, a, e) - p).norm() < 1e-15);
        let j = spherical_jacobian(r, a, e);
        let h = 1e-7;
        for (k, (dr, da, de)) in [(h, 0.0, 0.0), (0.0, h, 0.0), (0.0, 0.0, h)].into_iter().enumerate() {
            let fd = (from_spherical(r + dr, a + da, e + de) - from_spherical(r - dr, a - da, e - de)) / (2.0 * h);
            assert!((fd - j.column(k)).norm() < 1e-7, "column {k}");
        }
    }

    #[test]
    fn beam_breaks_occur_at_the_stated_rate() {
        let mut b = BeamBreakProcess::new(NoiseStream::new(3, 4), 10.0 / 3600.0, 2.0);
        let (mut broken, n) = (0usize, 100 * 3600 * 10);
        for k in 0..n {
            if b.broken(k as f64 * 0.1) {
                broken += 1;
            }
        }
        // expected fraction ≈ rate·duration = 10/3600·2 = 0.556 %; 1000 breaks → ±~5 %
        let frac = broken as f64 / n as f64;
        assert!((frac / (10.0 / 3600.0 * 2.0) - 1.0).abs() < 0.15, "fraction broken {frac}");
    }
}
