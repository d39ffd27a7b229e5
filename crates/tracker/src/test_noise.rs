//! Standard normal samples for the unit tests (Box–Muller; rand 0.9 without rand_distr).

use rand::Rng;
use rand_chacha::ChaCha8Rng;

pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
