//! A least-squares periodogram of residuals against an axis position: the period whose sine and
//! cosine explain most of the residual. It finds a screw's cyclic error whatever its lead, so the
//! candidate leads are not limited to a list (nor to what any simulator uses).

/// The number of independent frequencies between 1/max_period and 1/min_period over a span of
/// positions: (f_max − f_min)·span (frequencies closer than 1/span cannot be told apart).
pub fn independent_frequencies(span: f64, min_period: f64, max_period: f64) -> f64 {
    ((1.0 / min_period - 1.0 / max_period) * span).max(1.0)
}

/// The period (in the unit of `position`) in [min_period, max_period] whose fitted sinusoid
/// (with a constant) explains the largest share of `residual`'s weighted sum of squares, and
/// that share; None with fewer than 12 samples or no variation in position.
pub fn strongest_period(
    position: &[f64],
    residual: &[f64],
    weight: &[f64],
    min_period: f64,
    max_period: f64,
) -> Option<(f64, f64)> {
    let n = position.len();
    if n < 12 || !(max_period > min_period && min_period > 0.0) {
        return None;
    }
    let (lo, hi) = position
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| {
            (a.min(q), b.max(q))
        });
    if !(hi - lo > min_period) {
        return None;
    }
    let wsum: f64 = weight.iter().sum();
    let mean = position
        .iter()
        .zip(residual)
        .zip(weight)
        .map(|((_, r), w)| r * w)
        .sum::<f64>()
        / wsum;
    let total: f64 = residual
        .iter()
        .zip(weight)
        .map(|(r, w)| w * (r - mean).powi(2))
        .sum();
    if !(total > 0.0) {
        return None;
    }
    // frequencies spaced by a fraction of the resolution 1/span
    let (f_lo, f_hi) = (1.0 / max_period, 1.0 / min_period);
    let step = 0.2 / (hi - lo);
    let count = (((f_hi - f_lo) / step).ceil() as usize).min(20_000);
    let mut best: Option<(f64, f64)> = None;
    for k in 0..=count {
        let f = f_lo + (f_hi - f_lo) * k as f64 / count.max(1) as f64;
        let w = std::f64::consts::TAU * f;
        // weighted normal equations of [1, cos, sin]
        let mut g = nalgebra::Matrix3::<f64>::zeros();
        let mut h = nalgebra::Vector3::<f64>::zeros();
        for i in 0..n {
            let (s, c) = (w * position[i]).sin_cos();
            let a = nalgebra::Vector3::new(1.0, c, s);
            g += a * a.transpose() * weight[i];
            h += a * (residual[i] * weight[i]);
        }
        let Some(inv) = g.try_inverse() else { continue };
        let x = inv * h;
        let explained = x.dot(&h) - mean * mean * wsum;
        let share = explained / total;
        if share.is_finite() && best.is_none_or(|(_, b)| share > b) {
            best = Some((1.0 / f, share));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_an_odd_lead_among_noise() {
        let n = 400;
        // irregular positions (a regular grid has aliases the data cannot tell from the truth)
        let q: Vec<f64> = (0..n)
            .map(|i| 0.8 * (i as f64 * 0.618_033_988_75).fract())
            .collect();
        let r: Vec<f64> = q
            .iter()
            .enumerate()
            .map(|(i, x)| {
                3e-6 * (std::f64::consts::TAU * x / 0.0137).cos()
                    + 2e-6 * (((i * 31) % 17) as f64 / 8.0 - 1.0)
            })
            .collect();
        let (p, share) = strongest_period(&q, &r, &vec![1.0; n], 0.002, 0.2).unwrap();
        assert!((p - 0.0137).abs() < 2e-5, "{p}");
        assert!(share > 0.5);
    }
}
