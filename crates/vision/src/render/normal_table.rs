//! Fast seeded Gaussian deviates for sensor noise: 16 random bits pick one of 2¹⁶ equiprobable
//! quantiles of the standard normal, Φ⁻¹((k + ½)/2¹⁶), so one 64-bit draw gives four deviates
//! with a table load each (Box–Muller needs a log, a root and a cosine per deviate).
//!
//! The distribution is the normal's, discretised into 2¹⁶ equal-probability steps and cut at
//! ±4.17σ (probability 3·10⁻⁵ beyond); the table is rescaled so its variance is exactly 1.
//! For noise that is added to grey levels and rounded to integers the difference is far below
//! anything measurable.

use std::sync::OnceLock;

/// Bits per deviate.
pub(super) const BITS: u32 = 16;

/// The quantile table (2^BITS entries, symmetric, mean 0, variance 1).
pub(super) fn table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let n = 1usize << BITS;
        let q: Vec<f64> = (0..n)
            .map(|k| inverse_normal_cdf((k as f64 + 0.5) / n as f64))
            .collect();
        let var = q.iter().map(|v| v * v).sum::<f64>() / n as f64;
        let s = 1.0 / var.sqrt();
        q.iter().map(|v| (v * s) as f32).collect()
    })
}

/// Φ⁻¹(p) for 0 < p < 1 (Acklam's rational approximation, relative error < 1.2·10⁻⁹).
fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383_577_518_672_69e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    const P_LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_cdf_matches_known_quantiles() {
        // Φ(1) = 0.841344746068543, Φ(1.959963984540054) = 0.975, Φ(−3) = 0.001349898031630.
        for (p, z) in [
            (0.5, 0.0),
            (0.841344746068543, 1.0),
            (0.975, 1.959963984540054),
            (0.001349898031630, -3.0),
        ] {
            assert!(
                (inverse_normal_cdf(p) - z).abs() < 1e-8,
                "Φ⁻¹({p}) = {} ≠ {z}",
                inverse_normal_cdf(p)
            );
        }
    }

    #[test]
    fn table_has_the_moments_and_tails_of_a_standard_normal() {
        let t = table();
        let n = t.len() as f64;
        let mean = t.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = t.iter().map(|&v| (v as f64).powi(2)).sum::<f64>() / n;
        let kurt = t.iter().map(|&v| (v as f64).powi(4)).sum::<f64>() / n;
        assert!(
            mean.abs() < 1e-9 && (var - 1.0).abs() < 1e-6,
            "mean {mean}, var {var}"
        );
        assert!((kurt - 3.0).abs() < 0.01, "fourth moment {kurt}, normal 3");
        // P(|z| > 2) = 0.0455.
        let beyond2 = t.iter().filter(|v| v.abs() > 2.0).count() as f64 / n;
        assert!((beyond2 - 0.0455).abs() < 2e-4, "{beyond2}");
        assert!(t.windows(2).all(|w| w[0] < w[1]), "quantiles increase");
    }
}
