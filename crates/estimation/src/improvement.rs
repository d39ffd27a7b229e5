//! Before/after statistics of error magnitudes and the percent improvement, as seed 000 reports
//! a compensation (its Table 3).
//!
//! Quartiles interpolate linearly between order statistics (Hyndman–Fan type 7, numpy's
//! default); the standard deviation is the sample one (n − 1). Improvement is
//! (|before| − |after|)/|before|·100 %, on absolute values so a mean that changes sign still
//! counts by how much closer to zero it came (seed 000, §6.5).

/// Summary of a set of error values (same unit as the values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorStatistics {
    pub max: f64,
    pub q3: f64,
    pub median: f64,
    pub q1: f64,
    pub min: f64,
    pub mean: f64,
    pub sd: f64,
}

impl ErrorStatistics {
    /// Statistics of `values`; `None` when there are fewer than two finite values.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.len() < 2 {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        Some(Self {
            max: v[v.len() - 1],
            q3: quantile(&v, 0.75),
            median: quantile(&v, 0.5),
            q1: quantile(&v, 0.25),
            min: v[0],
            mean,
            sd,
        })
    }

    /// The statistics in Table 3's order, with their names.
    pub fn named(&self) -> [(&'static str, f64); 7] {
        [
            ("max", self.max),
            ("q3", self.q3),
            ("median", self.median),
            ("q1", self.q1),
            ("min", self.min),
            ("mean", self.mean),
            ("sd", self.sd),
        ]
    }
}

/// Quantile q of sorted values, linear interpolation (type 7).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * q;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// (|before| − |after|)/|before|·100.
pub fn percent_improvement(before: f64, after: f64) -> f64 {
    (before.abs() - after.abs()) / before.abs() * 100.0
}

/// Percent improvement of every statistic, and their average (Table 3's last row).
pub fn improvement(
    before: &ErrorStatistics,
    after: &ErrorStatistics,
) -> ([(&'static str, f64); 7], f64) {
    let b = before.named();
    let a = after.named();
    let mut out = b;
    for (o, (bb, aa)) in out.iter_mut().zip(b.iter().zip(a.iter())) {
        o.1 = percent_improvement(bb.1, aa.1);
    }
    let average = out.iter().map(|x| x.1).sum::<f64>() / out.len() as f64;
    (out, average)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(v: [f64; 7]) -> ErrorStatistics {
        ErrorStatistics {
            max: v[0],
            q3: v[1],
            median: v[2],
            q1: v[3],
            min: v[4],
            mean: v[5],
            sd: v[6],
        }
    }

    /// Seed 000 Table 3 (digest test case T1): every improvement to 0.01 %.
    #[test]
    fn seed000_table3_improvements() {
        let initial = table([2.4146, 2.0117, 1.5541, 1.0926, 0.3427, 1.5378, 0.5288]);
        let b12 = table([0.9392, 0.6142, 0.4692, 0.3809, 0.1650, 0.4951, 0.1806]);
        let b72 = table([1.1038, 0.7347, 0.6192, 0.4478, 0.2415, 0.6252, 0.2202]);
        let expect12 = [61.10, 69.47, 69.81, 65.14, 51.85, 67.80, 65.85];
        let expect72 = [54.29, 63.48, 60.16, 59.02, 29.53, 59.34, 58.36];
        for (after, expect, avg) in [(b12, expect12, 64.43), (b72, expect72, 54.88)] {
            let (got, average) = improvement(&initial, &after);
            for ((name, g), e) in got.iter().zip(expect) {
                assert!((g - e).abs() < 0.005 + 1e-9, "{name}: {g:.4} vs {e}");
            }
            assert!((average - avg).abs() < 0.005 + 1e-9, "average {average}");
        }
        // per-direction checks of §6.5 (absolute values: the y mean changes sign)
        assert!((percent_improvement(1.39, -0.066) - 95.25).abs() < 0.005);
        assert!((percent_improvement(0.422, 0.182) - 56.87).abs() < 0.005);
    }

    #[test]
    fn statistics_of_values() {
        let s = ErrorStatistics::of(&[4.0, 1.0, 3.0, 2.0, f64::NAN]).unwrap();
        assert_eq!(
            (s.min, s.max, s.median, s.q1, s.q3, s.mean),
            (1.0, 4.0, 2.5, 1.75, 3.25, 2.5)
        );
        assert!((s.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!(ErrorStatistics::of(&[1.0]).is_none());
    }
}
