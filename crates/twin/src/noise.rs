//! Seeded random streams. Every noise source draws from its own ChaCha8 stream
//! (`seed_from_u64(seed)` + `set_stream(id)`), so adding a sensor never changes the noise of
//! another and the whole simulation is a pure function of (cell, duration, seed).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Stream ids of the noise sources (stable: part of the determinism contract).
pub mod stream {
    pub const THERMAL_WALK: u64 = 1;
    pub const TRACKER: u64 = 2;
    pub const STATION: u64 = 3;
    pub const BEAM_BREAKS: u64 = 4;
    pub const PROBE: u64 = 5;
    /// A stationing program's setups' residual tilts, its plan (seeded by the program's own
    /// seed), the instrument's point noise.
    pub const SETUP_TILT: u64 = 6;
    pub const STATIONING_PLAN: u64 = 7;
    pub const STATION_POINT: u64 = 8;
    /// Accelerometer i uses ACCELEROMETER_BASE + i.
    pub const ACCELEROMETER_BASE: u64 = 2000;
    /// Thermocouple i uses THERMOCOUPLE_BASE + i.
    pub const THERMOCOUPLE_BASE: u64 = 1000;
}

/// A seeded source of standard normal and uniform variates.
#[derive(Debug, Clone)]
pub struct NoiseStream {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl NoiseStream {
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Self { rng, spare: None }
    }

    /// Standard normal variate (Box–Muller, both values used).
    pub fn normal(&mut self) -> f64 {
        if let Some(v) = self.spare.take() {
            return v;
        }
        let u1: f64 = 1.0 - self.rng.random::<f64>();
        let u2: f64 = self.rng.random::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }

    /// Uniform on [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// Exponential variate with the given mean.
    pub fn exponential(&mut self, mean: f64) -> f64 {
        -mean * (1.0 - self.uniform()).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_has_unit_variance_and_streams_differ() {
        let mut a = NoiseStream::new(7, 1);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| a.normal()).collect();
        let m = xs.iter().sum::<f64>() / n as f64;
        let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        assert!(m.abs() < 0.01, "mean {m}");
        assert!((v - 1.0).abs() < 0.01, "variance {v}");
        let mut b = NoiseStream::new(7, 2);
        let mut a2 = NoiseStream::new(7, 1);
        assert_ne!(a2.normal(), b.normal());
    }
}
