//! The turbulence test: is a dwell's range scatter larger than the noise model predicts?
//!
//! Thesis P1 §3: turbulent air over the beam raises the RMS of a fixed target's range from the
//! instrument's 2–8 µm to ~70 µm; the proposed rule compares the RMS with the expected
//! uncertainty. Stated here as a test with a known false-alarm rate: for N readings of a target
//! that does not move, with per-reading σ from the noise model (a + b·range),
//! X = Σ (ρ_i − ρ̄)² / σ² follows χ²(N − 1) when the air is quiet; the dwell is flagged when X
//! exceeds the (1 − α) quantile. α is the fraction of quiet dwells flagged.

/// The χ² scatter test at false-alarm rate `false_alarm` (per dwell).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurbulenceTest {
    pub false_alarm: f64,
}

/// The outcome for one dwell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurbulenceVerdict {
    /// Σ (ρ_i − ρ̄)² / σ²
    pub statistic: f64,
    /// χ²(dof) quantile at 1 − false_alarm
    pub threshold: f64,
    pub dof: usize,
    /// observed RMS / expected σ (1 on average in quiet air)
    pub scatter_ratio: f64,
    pub flagged: bool,
}

impl TurbulenceTest {
    /// The verdict for `ranges` (m) with expected per-reading σ `sigma` (m); `None` with fewer
    /// than two readings or σ ≤ 0 (nothing to compare).
    pub fn test(&self, ranges: &[f64], sigma: f64) -> Option<TurbulenceVerdict> {
        if ranges.len() < 2 || !(sigma > 0.0) {
            return None;
        }
        let n = ranges.len() as f64;
        let mean = ranges.iter().sum::<f64>() / n;
        let ss = ranges.iter().map(|r| (r - mean).powi(2)).sum::<f64>();
        let dof = ranges.len() - 1;
        let statistic = ss / (sigma * sigma);
        let threshold = chi_squared_quantile(dof as f64, 1.0 - self.false_alarm);
        Some(TurbulenceVerdict {
            statistic,
            threshold,
            dof,
            scatter_ratio: (ss / dof as f64).sqrt() / sigma,
            flagged: statistic > threshold,
        })
    }
}

/// Quantile of χ²(k) at probability p, by bisection on the regularized lower incomplete gamma
/// function P(k/2, x/2) (accurate to ~1e-10 relative; p in (0, 1)).
pub fn chi_squared_quantile(k: f64, p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, k.max(1.0));
    while regularized_gamma_p(k / 2.0, hi / 2.0) < p {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if regularized_gamma_p(k / 2.0, mid / 2.0) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-12 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// P(a, x) = γ(a, x)/Γ(a): series below a + 1, Lentz continued fraction above (Numerical Recipes §6.2).
fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let ln_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        sum * ln_prefactor.exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        1.0 - ln_prefactor.exp() * h
    }
}

/// ln Γ(x), Lanczos (g = 7, 9 terms), x > 0.
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_noise::normal;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn quantiles_match_tables() {
        // standard χ² table values (4–5 significant digits)
        for (k, p, q) in [
            (1.0, 0.95, 3.8415),
            (4.0, 0.95, 9.4877),
            (10.0, 0.99, 23.209),
            (29.0, 0.999, 58.301),
            (99.0, 0.99, 134.64),
        ] {
            let got = chi_squared_quantile(k, p);
            assert!((got - q).abs() < 1e-4 * q, "χ²({k}) at {p}: {got} vs {q}");
        }
    }

    #[test]
    fn false_alarm_rate_is_as_stated_in_quiet_air() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let test = TurbulenceTest { false_alarm: 0.01 };
        let sigma = 5.6e-6;
        let trials = 20_000;
        let flagged = (0..trials)
            .filter(|_| {
                let ranges: Vec<f64> = (0..30).map(|_| 2.0 + sigma * normal(&mut rng)).collect();
                test.test(&ranges, sigma).unwrap().flagged
            })
            .count();
        // binomial(20000, 0.01): 200 ± 14
        assert!(
            (155..=245).contains(&flagged),
            "{flagged} of {trials} flagged"
        );
    }

    #[test]
    fn thesis_turbulence_is_flagged() {
        // thesis P1: RMS ~70 µm in turbulence vs σ ≈ 5.6 µm expected at 2 m
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let test = TurbulenceTest { false_alarm: 0.001 };
        for _ in 0..100 {
            let ranges: Vec<f64> = (0..30).map(|_| 2.0 + 70e-6 * normal(&mut rng)).collect();
            let v = test.test(&ranges, 5.6e-6).unwrap();
            assert!(v.flagged && v.scatter_ratio > 5.0, "{v:?}");
        }
        assert!(test.test(&[2.0], 5.6e-6).is_none());
    }
}
