//! Monte Carlo propagation: re-solve with simulated measurement noise and take the empirical
//! covariance of the solutions (seeded, so a run repeats bit for bit).

use crate::error::{check_finite, SolverError};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The noise added to the measurements in each trial.
#[derive(Debug, Clone, PartialEq)]
pub enum Noise {
    /// Independent, zero-mean, with these standard deviations.
    Independent(Vec<f64>),
    /// Zero-mean Gaussian with this (symmetric, positive semi-definite) covariance.
    Correlated(DMatrix<f64>),
}

/// The spread of the solutions over the trials.
#[derive(Debug, Clone, PartialEq)]
pub struct MonteCarlo {
    pub mean: DVector<f64>,
    /// Empirical covariance (divisor: successful trials − 1).
    pub covariance: DMatrix<f64>,
    pub trials: usize,
    /// Trials whose solve returned None (not included in the statistics).
    pub failures: usize,
}

/// A standard normal draw (Box–Muller; one of the pair is used, which keeps the stream simple).
fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Runs `trials` solves: each draws a noise vector from `noise` with a ChaCha8 stream seeded by
/// `seed` and passes it to `solve`, which adds it to its measurements and returns the estimate
/// (None if that trial's solve failed).
pub fn monte_carlo<F>(
    trials: usize,
    seed: u64,
    noise: &Noise,
    mut solve: F,
) -> Result<MonteCarlo, SolverError>
where
    F: FnMut(&DVector<f64>) -> Option<DVector<f64>>,
{
    // Noise = factor · z, z standard normal.
    enum Factor {
        Diagonal(DVector<f64>),
        Full(DMatrix<f64>),
    }
    let factor = match noise {
        Noise::Independent(s) => {
            check_finite("noise standard deviations", s)?;
            if let Some(i) = s.iter().position(|v| *v < 0.0) {
                return Err(SolverError::Invalid {
                    what: format!("noise standard deviation [{i}]"),
                    reason: "negative".into(),
                });
            }
            Factor::Diagonal(DVector::from_column_slice(s))
        }
        Noise::Correlated(c) => {
            check_finite("noise covariance", c.as_slice())?;
            if !c.is_square() {
                return Err(SolverError::Invalid {
                    what: "noise covariance".into(),
                    reason: format!("not square ({}×{})", c.nrows(), c.ncols()),
                });
            }
            // Symmetric square root V·√Λ, which also covers semi-definite covariances.
            let eig = c.clone().symmetric_eigen();
            let min = eig.eigenvalues.min();
            if min < -1e-12 * eig.eigenvalues.amax() {
                return Err(SolverError::Invalid {
                    what: "noise covariance".into(),
                    reason: format!("not positive semi-definite (eigenvalue {min:e})"),
                });
            }
            Factor::Full(
                &eig.eigenvectors
                    * DMatrix::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0).sqrt())),
            )
        }
    };
    let dim = match noise {
        Noise::Independent(s) => s.len(),
        Noise::Correlated(c) => c.nrows(),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut solutions: Vec<DVector<f64>> = Vec::with_capacity(trials);
    let mut failures = 0;
    let mut z = DVector::zeros(dim);
    for _ in 0..trials {
        z.iter_mut().for_each(|v| *v = standard_normal(&mut rng));
        let e = match &factor {
            Factor::Full(l) => l * &z,
            Factor::Diagonal(s) => z.component_mul(s),
        };
        match solve(&e) {
            Some(x) if x.iter().all(|v| v.is_finite()) => solutions.push(x),
            _ => failures += 1,
        }
    }
    let ok = solutions.len();
    if ok < 2 {
        return Err(SolverError::Invalid {
            what: "Monte Carlo".into(),
            reason: format!("only {ok} of {trials} trials succeeded; need at least 2"),
        });
    }
    let p = solutions[0].len();
    if let Some(i) = solutions.iter().position(|s| s.len() != p) {
        return Err(SolverError::Length {
            what: format!("Monte Carlo trial solution {i}"),
            expected: p,
            got: solutions[i].len(),
        });
    }
    let mean = solutions.iter().fold(DVector::zeros(p), |a, s| a + s) / ok as f64;
    let mut covariance = DMatrix::zeros(p, p);
    for s in &solutions {
        let d = s - &mean;
        covariance += &d * d.transpose();
    }
    covariance /= (ok - 1) as f64;
    Ok(MonteCarlo {
        mean,
        covariance,
        trials,
        failures,
    })
}
