//! Straight-line fit of a time series: the drift rate (slope) and the value the line predicts
//! now, each with its standard uncertainty.
//!
//! Ordinary least squares on (t, v) with t taken relative to the mean time (so that seconds since
//! the Unix epoch lose no digits). The uncertainties come from the scatter about the line
//! (s² = Σr²/(n−2)), so they grow with noise and shrink with more samples and a longer window:
//! σ(slope) = s/√Sₜₜ, σ(value at t) = s·√(1/n + (t−t̄)²/Sₜₜ).

use serde::Serialize;

/// A fitted line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Trend {
    /// Slope [unit of v per second].
    pub rate: f64,
    /// Standard uncertainty of the slope.
    pub rate_sigma: f64,
    /// The line's value at the latest sample time.
    pub value: f64,
    /// Standard uncertainty of that value.
    pub value_sigma: f64,
    /// Samples in the fit.
    pub samples: usize,
    /// Time spanned by the samples [s].
    pub span: f64,
}

/// Fit a line through `(t [s], v)` samples. `None` with fewer than 3 samples or when all
/// samples share one time (no slope is defined).
pub fn fit_line<'a>(samples: impl IntoIterator<Item = &'a (f64, f64)> + Clone) -> Option<Trend> {
    let (mut n, mut st, mut sv) = (0usize, 0.0, 0.0);
    let (mut t_min, mut t_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(t, v) in samples.clone() {
        n += 1;
        st += t;
        sv += v;
        t_min = t_min.min(t);
        t_max = t_max.max(t);
    }
    if n < 3 {
        return None;
    }
    let (t_mean, v_mean) = (st / n as f64, sv / n as f64);
    let (mut stt, mut stv) = (0.0, 0.0);
    for &(t, v) in samples.clone() {
        stt += (t - t_mean) * (t - t_mean);
        stv += (t - t_mean) * (v - v_mean);
    }
    if stt <= 0.0 {
        return None;
    }
    let rate = stv / stt;
    let ssr: f64 = samples
        .into_iter()
        .map(|&(t, v)| (v - v_mean - rate * (t - t_mean)).powi(2))
        .sum();
    let s = (ssr / (n - 2) as f64).sqrt();
    let dt = t_max - t_mean;
    Some(Trend {
        rate,
        rate_sigma: s / stt.sqrt(),
        value: v_mean + rate * dt,
        value_sigma: s * (1.0 / n as f64 + dt * dt / stt).sqrt(),
        samples: n,
        span: t_max - t_min,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_ramp_gives_its_slope_and_end_value_with_zero_uncertainty() {
        // 5 µm + 120 µm/h, sampled every 10 s for an hour, at epoch-sized times
        let t0 = 1.7e9;
        let s: Vec<(f64, f64)> = (0..=360)
            .map(|k| {
                (
                    t0 + 10.0 * k as f64,
                    5e-6 + 120e-6 / 3600.0 * 10.0 * k as f64,
                )
            })
            .collect();
        let f = fit_line(&s).unwrap();
        assert!(
            (f.rate * 3600.0 - 120e-6).abs() < 1e-12,
            "rate {} m/h",
            f.rate * 3600.0
        );
        assert!((f.value - 125e-6).abs() < 1e-12, "end value {}", f.value);
        assert!(f.rate_sigma < 1e-15 && f.value_sigma < 1e-12);
        assert_eq!((f.samples, f.span), (361, 3600.0));
    }

    #[test]
    fn noisy_ramp_slope_within_its_uncertainty_and_sigma_matches_theory() {
        // alternating ±1 µm noise on a 60 µm/h ramp: residual s ≈ 1 µm, σ(slope) = s/√Stt
        let s: Vec<(f64, f64)> = (0..100)
            .map(|k| {
                (
                    k as f64,
                    60e-6 / 3600.0 * k as f64 + if k % 2 == 0 { 1e-6 } else { -1e-6 },
                )
            })
            .collect();
        let f = fit_line(&s).unwrap();
        let stt: f64 = (0..100).map(|k| (k as f64 - 49.5).powi(2)).sum();
        assert!(
            (f.rate_sigma - 1e-6 / stt.sqrt()).abs() < 0.02 * f.rate_sigma,
            "σ {}",
            f.rate_sigma
        );
        assert!((f.rate - 60e-6 / 3600.0).abs() < 2.0 * f.rate_sigma);
    }

    #[test]
    fn too_few_or_simultaneous_samples_have_no_trend() {
        assert!(fit_line(&[(0.0, 1.0), (1.0, 2.0)]).is_none());
        assert!(fit_line(&[(3.0, 1.0), (3.0, 2.0), (3.0, 4.0)]).is_none());
    }
}
