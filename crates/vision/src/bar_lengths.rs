//! Lengths of printed bars measured between two edges in an image (seed 002's calibration star):
//! the plausibility filter that drops edges found on the wrong feature, and the length's
//! uncertainty from the edge finder's pixel error and the plane scale.
//!
//! The paper bounds its length error by "±4 px at each end" and adds the two ends linearly:
//! 2 × 4 px × 0.07226 mm/px = 0.578 mm ([`worst_case_length_error`]). That is a bound, not a
//! standard uncertainty: with the two ends independent and each error uniform within ±a, the
//! GUM standard uncertainty is a/√3 per end and √2·a/√3·scale for the length
//! ([`length_standard_uncertainty`]) — 0.236 mm for the paper's figures, which is what an
//! uncertainty budget combines with the other terms.

use crate::error::{invalid, Result};

/// Lengths kept by [`filter_lengths`], the ones dropped (with their index) and the kept mean.
#[derive(Debug, Clone, PartialEq)]
pub struct FilteredLengths {
    pub kept: Vec<f64>,
    pub rejected: Vec<(usize, f64)>,
    /// Mean of the kept lengths; `None` when none is kept.
    pub mean: Option<f64>,
}

/// Keep the lengths within `[min, max]` (inclusive; the expected bar length ± what a good
/// measurement can be off by). Non-finite lengths are rejected like implausible ones.
pub fn filter_lengths(lengths: &[f64], min: f64, max: f64) -> Result<FilteredLengths> {
    if !(min.is_finite() && max.is_finite() && min < max) {
        return Err(invalid(
            "length filter",
            format!("[{min}, {max}] is not an interval: give min < max, both finite"),
        ));
    }
    let (mut kept, mut rejected) = (Vec::new(), Vec::new());
    for (i, &l) in lengths.iter().enumerate() {
        if l.is_finite() && (min..=max).contains(&l) {
            kept.push(l);
        } else {
            rejected.push((i, l));
        }
    }
    let mean = (!kept.is_empty()).then(|| kept.iter().sum::<f64>() / kept.len() as f64);
    Ok(FilteredLengths {
        kept,
        rejected,
        mean,
    })
}

/// The paper's bound on a length's error: each end off by at most `px_per_end` pixels, the two
/// ends added linearly, times the plane `scale` (length per pixel).
pub fn worst_case_length_error(px_per_end: f64, scale: f64) -> f64 {
    2.0 * px_per_end * scale
}

/// Standard uncertainty of a length whose two ends are each off by an independent error uniform
/// within ±`px_bound_per_end` pixels, times the plane `scale`.
pub fn length_standard_uncertainty(px_bound_per_end: f64, scale: f64) -> f64 {
    std::f64::consts::SQRT_2 * px_bound_per_end / 3f64.sqrt() * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_interval_is_refused() {
        assert!(filter_lengths(&[1.0], 2.0, 1.0).is_err());
        assert!(filter_lengths(&[1.0], f64::NAN, 1.0).is_err());
    }

    #[test]
    fn non_finite_lengths_are_rejected_not_averaged() {
        let f = filter_lengths(&[100.0, f64::NAN, 101.0], 90.0, 110.0).unwrap();
        assert_eq!(f.kept, [100.0, 101.0]);
        assert_eq!(f.rejected.len(), 1);
        assert_eq!(f.mean, Some(100.5));
        assert_eq!(filter_lengths(&[5.0], 90.0, 110.0).unwrap().mean, None);
    }
}
