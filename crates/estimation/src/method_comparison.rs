//! Agreement of a measuring method with a reference method on the same parts, as seed 002's
//! Table 2 compares its optical lengths with a vernier caliper's: per part the absolute
//! difference |method − reference| and the relative one (absolute / reference), then their means.
//!
//! The paper's Table 2 rounds the relative errors to two decimals (1.00 %, 0.84 %, 0.40 %) and
//! states a mean of 0.75 %; computed from its printed lengths they are 0.9988 %, 0.8399 %,
//! 0.3976 % and 0.7454 % (seed 002 digest, T1). A mean of absolute differences is not a bias: a
//! method that reads 1 mm long on one part and 1 mm short on the next has mean |difference| 1 mm
//! and bias 0, so the signed mean is reported too.

/// One part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartComparison {
    pub reference: f64,
    pub method: f64,
    /// |method − reference|.
    pub absolute: f64,
    /// |method − reference| / |reference| (a fraction; ×100 for %).
    pub relative: f64,
}

/// All parts and the means.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodComparison {
    pub parts: Vec<PartComparison>,
    pub mean_reference: f64,
    pub mean_method: f64,
    pub mean_absolute: f64,
    pub mean_relative: f64,
    /// Mean of method − reference (signed).
    pub bias: f64,
}

/// Compare `method` with `reference`, part by part (same order, same unit).
pub fn compare_methods(reference: &[f64], method: &[f64]) -> Result<MethodComparison, String> {
    if reference.len() != method.len() {
        return Err(format!(
            "{} reference values and {} method values: give one of each per part",
            reference.len(),
            method.len()
        ));
    }
    if reference.is_empty() {
        return Err("no parts to compare".into());
    }
    let mut parts = Vec::with_capacity(reference.len());
    for (i, (&r, &m)) in reference.iter().zip(method).enumerate() {
        if !r.is_finite() || !m.is_finite() || r == 0.0 {
            return Err(format!(
                "part {}: reference {r} and method {m} must be finite, the reference non-zero",
                i + 1
            ));
        }
        let absolute = (m - r).abs();
        parts.push(PartComparison {
            reference: r,
            method: m,
            absolute,
            relative: absolute / r.abs(),
        });
    }
    let mean =
        |f: &dyn Fn(&PartComparison) -> f64| parts.iter().map(f).sum::<f64>() / parts.len() as f64;
    Ok(MethodComparison {
        mean_reference: mean(&|p| p.reference),
        mean_method: mean(&|p| p.method),
        mean_absolute: mean(&|p| p.absolute),
        mean_relative: mean(&|p| p.relative),
        bias: mean(&|p| p.method - p.reference),
        parts,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_bias_is_not_the_mean_absolute_difference() {
        let c = compare_methods(&[10.0, 10.0], &[11.0, 9.0]).unwrap();
        assert_eq!(c.mean_absolute, 1.0);
        assert_eq!(c.bias, 0.0);
    }

    #[test]
    fn bad_input_is_named() {
        assert!(compare_methods(&[1.0], &[1.0, 2.0])
            .unwrap_err()
            .contains("one of each per part"));
        assert!(compare_methods(&[1.0, 0.0], &[1.0, 2.0])
            .unwrap_err()
            .starts_with("part 2"));
    }
}
