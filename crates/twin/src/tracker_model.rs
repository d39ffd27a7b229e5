//! Laser-tracker measurement model (pure functions plus the seeded beam-break process).
//!
//! Spherical coordinates and their covariance: [`metrocell_physics::instrument::spherical`].
//!
//! What the tracker reads for a target at true spherical (ρ, θ, φ):
//! * range: ρ_m = ρ + Δρ_refraction + Δρ_warmup + σ_eff·N(0,1), the first three from the shared
//!   forward model ([`metrocell_model::forward`]: the `refraction` term — the interferometer
//!   counts the true optical path and divides by the index from its own weather station,
//!   thesis P1 eq. 10, one section — and the `tracker_warmup` term, thesis eq. 3.1), and
//!   σ_eff = √((a + bρ)² + (cρ)²) (physics `turbulence`: c > 0 only inside turbulence windows);
//! * angles: θ_m = θ + σ_ang·N, φ_m = φ + σ_ang·N.
//!
//! The *stated* covariance of a sample is what the instrument believes: σ_ρ = a + b·ρ and σ_ang,
//! propagated through the spherical→Cartesian Jacobian. Turbulence is therefore visible as
//! scatter above the stated σ (flagged downstream, never fitted as bias).

pub use metrocell_physics::instrument::spherical::{
    from_spherical, point_covariance, spherical_jacobian, to_spherical,
};

use crate::noise::NoiseStream;

/// Stated range σ, a + b·ρ.
pub fn stated_range_sigma(constant: f64, per_metre: f64, rho: f64) -> f64 {
    constant + per_metre * rho
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
        let mut p = Self {
            rng,
            rate,
            mean_duration,
            start: f64::INFINITY,
            end: f64::NEG_INFINITY,
        };
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
        assert!(
            (frac / (10.0 / 3600.0 * 2.0) - 1.0).abs() < 0.15,
            "fraction broken {frac}"
        );
    }
}
