//! Are the residuals what the stated noise predicts? Per channel and axis, on the normalised
//! residuals z = r/σ in time order:
//!
//! * χ²: Σz² against χ²(n) — too much scatter for the stated σ (upper tail);
//! * mean shift: √n·z̄ against N(0, 1) — a bias the model does not carry (two-sided);
//! * Ljung–Box: n(n+2)·Σₖ ρₖ²/(n−k) over h lags against χ²(h) — correlation in time;
//! * runs: the number of sign runs against its Wald–Wolfowitz distribution (two-sided).
//!
//! Whiteness and runs assume the samples are in time order; [`noise_report`] sorts them.

use std::collections::BTreeMap;

use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

use crate::multiple_testing::holm;
use crate::residual::ResidualSample;

/// One test's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseTest {
    pub name: &'static str,
    pub statistic: f64,
    pub p_value: f64,
    /// After correction for every test in the report.
    pub p_adjusted: f64,
}

/// The tests of one channel and axis.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelNoise {
    pub channel: String,
    pub axis: usize,
    pub count: usize,
    /// RMS of the residuals (m) and the RMS the stated σ predict (m).
    pub rms_m: f64,
    pub noise_rms_m: f64,
    pub chi2_per_dof: f64,
    pub tests: Vec<NoiseTest>,
}

impl ChannelNoise {
    /// No test rejects at `alpha` after correction.
    pub fn consistent_with_noise(&self, alpha: f64) -> bool {
        self.tests.iter().all(|t| t.p_adjusted > alpha)
    }
}

fn standard_normal() -> Normal {
    Normal::new(0.0, 1.0).expect("unit normal")
}

/// χ² of normalised residuals against χ²(n), upper tail.
pub fn chi_square(z: &[f64]) -> (f64, f64) {
    let s: f64 = z.iter().map(|v| v * v).sum();
    let n = z.len() as f64;
    let p = ChiSquared::new(n).map(|d| d.sf(s)).unwrap_or(f64::NAN);
    (s, p)
}

/// √n·mean(z) against N(0, 1), two-sided.
pub fn mean_shift(z: &[f64]) -> (f64, f64) {
    let n = z.len() as f64;
    let t = z.iter().sum::<f64>() / n.sqrt();
    (t, 2.0 * standard_normal().sf(t.abs()))
}

/// Ljung–Box Q over `lags` lags against χ²(lags).
pub fn ljung_box(z: &[f64], lags: usize) -> (f64, f64) {
    let n = z.len();
    let mean = z.iter().sum::<f64>() / n as f64;
    let c0: f64 = z.iter().map(|v| (v - mean).powi(2)).sum();
    if c0 == 0.0 || lags == 0 || lags >= n {
        return (0.0, 1.0);
    }
    let mut q = 0.0;
    for k in 1..=lags {
        let ck: f64 = (k..n).map(|i| (z[i] - mean) * (z[i - k] - mean)).sum();
        let rho = ck / c0;
        q += rho * rho / (n - k) as f64;
    }
    q *= n as f64 * (n as f64 + 2.0);
    (
        q,
        ChiSquared::new(lags as f64)
            .map(|d| d.sf(q))
            .unwrap_or(f64::NAN),
    )
}

/// Wald–Wolfowitz runs test on the signs of z (zeros dropped): z-score of the run count and its
/// two-sided p-value.
pub fn runs_test(z: &[f64]) -> (f64, f64) {
    let signs: Vec<bool> = z.iter().filter(|v| **v != 0.0).map(|v| *v > 0.0).collect();
    let n1 = signs.iter().filter(|s| **s).count() as f64;
    let n2 = signs.len() as f64 - n1;
    let n = n1 + n2;
    if n1 == 0.0 || n2 == 0.0 || n < 3.0 {
        return (0.0, 1.0);
    }
    let runs = 1.0 + signs.windows(2).filter(|w| w[0] != w[1]).count() as f64;
    let mu = 2.0 * n1 * n2 / n + 1.0;
    let var = 2.0 * n1 * n2 * (2.0 * n1 * n2 - n) / (n * n * (n - 1.0));
    let score = (runs - mu) / var.sqrt();
    (score, 2.0 * standard_normal().sf(score.abs()))
}

/// The four tests for every channel and axis with at least `min_count` samples, p-values
/// corrected together (Holm).
pub fn noise_report(samples: &[ResidualSample], min_count: usize) -> Vec<ChannelNoise> {
    let mut groups: BTreeMap<(String, usize), Vec<&ResidualSample>> = BTreeMap::new();
    for s in samples
        .iter()
        .filter(|s| s.residual.is_finite() && s.sigma > 0.0 && s.time.is_finite())
    {
        groups
            .entry((s.channel.clone(), s.axis))
            .or_default()
            .push(s);
    }
    let mut out = Vec::new();
    for ((channel, axis), mut g) in groups {
        if g.len() < min_count.max(3) {
            continue;
        }
        g.sort_by(|a, b| a.time.total_cmp(&b.time));
        let z: Vec<f64> = g.iter().map(|s| s.z()).collect();
        let n = z.len();
        let (chi2, p_chi2) = chi_square(&z);
        let (shift, p_shift) = mean_shift(&z);
        let lags = (n / 5).clamp(1, 10);
        let (q, p_q) = ljung_box(&z, lags);
        let (runs, p_runs) = runs_test(&z);
        let rms = (g.iter().map(|s| s.residual * s.residual).sum::<f64>() / n as f64).sqrt();
        let noise = (g.iter().map(|s| s.sigma * s.sigma).sum::<f64>() / n as f64).sqrt();
        out.push(ChannelNoise {
            channel,
            axis,
            count: n,
            rms_m: rms,
            noise_rms_m: noise,
            chi2_per_dof: chi2 / n as f64,
            tests: vec![
                NoiseTest {
                    name: "chi_square",
                    statistic: chi2,
                    p_value: p_chi2,
                    p_adjusted: f64::NAN,
                },
                NoiseTest {
                    name: "mean_shift",
                    statistic: shift,
                    p_value: p_shift,
                    p_adjusted: f64::NAN,
                },
                NoiseTest {
                    name: "ljung_box",
                    statistic: q,
                    p_value: p_q,
                    p_adjusted: f64::NAN,
                },
                NoiseTest {
                    name: "runs",
                    statistic: runs,
                    p_value: p_runs,
                    p_adjusted: f64::NAN,
                },
            ],
        });
    }
    let all: Vec<f64> = out
        .iter()
        .flat_map(|c| c.tests.iter().map(|t| t.p_value))
        .collect();
    let adjusted = holm(&all);
    let mut k = 0;
    for c in &mut out {
        for t in &mut c.tests {
            t.p_adjusted = adjusted[k];
            k += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms: χ²(4) survival is e^(−x/2)·(1 + x/2); 2·Φ(−1.25) = 0.211300.
    #[test]
    fn statistics_match_their_definitions() {
        let z = [1.0, -1.0, 2.0, 0.5];
        let (s, p) = chi_square(&z);
        assert_eq!(s, 6.25);
        assert!((p - (-3.125f64).exp() * 4.125).abs() < 1e-12, "{p}");
        let (t, p) = mean_shift(&z);
        assert!(
            (t - 1.25).abs() < 1e-12 && (p - 0.21130).abs() < 1e-5,
            "{t} {p}"
        );
        // alternating signs: as many runs as samples → far too many runs for chance
        let alt: Vec<f64> = (0..40)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let (score, p) = runs_test(&alt);
        assert!(score > 5.0 && p < 1e-6);
        // a slow sine is strongly autocorrelated
        let sine: Vec<f64> = (0..200).map(|i| (i as f64 / 20.0).sin()).collect();
        assert!(ljung_box(&sine, 10).1 < 1e-10);
    }
}
