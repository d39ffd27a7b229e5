//! Robust losses ρ(s) of the squared, whitened residual s = (r/σ)², written in units of the
//! loss's scale c: ρ(s) = c²·ρ₁(s/c²). ρ₁(s) = s for small s in every loss, so inliers count as
//! in plain least squares.

/// A loss on the squared whitened residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Loss {
    /// ρ(s) = s: ordinary least squares.
    Linear,
    /// Huber with threshold c (in σ): quadratic up to |r/σ| = c, linear beyond.
    Huber(f64),
    /// Cauchy (Lorentzian) with scale c (in σ): ρ₁(z) = ln(1 + z); outliers' influence vanishes.
    Cauchy(f64),
}

impl Loss {
    fn scale(&self) -> Option<f64> {
        match *self {
            Loss::Linear => None,
            Loss::Huber(c) | Loss::Cauchy(c) => Some(c),
        }
    }

    /// ρ(s) and ρ'(s) for a squared whitened residual s ≥ 0.
    pub fn evaluate(&self, s: f64) -> (f64, f64) {
        match *self {
            Loss::Linear => (s, 1.0),
            Loss::Huber(c) => {
                let c2 = c * c;
                if s <= c2 {
                    (s, 1.0)
                } else {
                    let r = s.sqrt();
                    (2.0 * c * r - c2, c / r)
                }
            }
            Loss::Cauchy(c) => {
                let c2 = c * c;
                (c2 * (s / c2).ln_1p(), 1.0 / (1.0 + s / c2))
            }
        }
    }

    /// Whether a squared whitened residual lies beyond the loss's scale (|r/σ| > c), where the
    /// loss stops being quadratic: the count of such residuals is reported as down-weighted.
    pub fn is_downweighted(&self, s: f64) -> bool {
        self.scale().is_some_and(|c| s > c * c)
    }

    pub(crate) fn validate(&self) -> Result<(), crate::SolverError> {
        match self.scale() {
            Some(c) if !(c.is_finite() && c > 0.0) => Err(crate::SolverError::Invalid {
                what: "loss scale".into(),
                reason: format!("must be finite and positive, got {c}"),
            }),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn losses_are_quadratic_inside_and_continuous_with_their_derivative() {
        for loss in [Loss::Huber(1.5), Loss::Cauchy(2.0)] {
            let (r0, d0) = loss.evaluate(1e-6);
            assert!(
                (r0 - 1e-6).abs() < 1e-12 && (d0 - 1.0).abs() < 1e-6,
                "{loss:?}"
            );
            for s in [0.5, 2.25, 3.0, 40.0] {
                let h = 1e-6 * s;
                let numeric = (loss.evaluate(s + h).0 - loss.evaluate(s - h).0) / (2.0 * h);
                assert!(
                    (numeric - loss.evaluate(s).1).abs() < 1e-6,
                    "{loss:?} at {s}"
                );
            }
        }
        // Huber beyond c: linear in |r| with slope 2c.
        let (rho, _) = Loss::Huber(1.0).evaluate(16.0);
        assert_eq!(rho, 7.0);
        assert!(Loss::Huber(1.0).is_downweighted(1.01) && !Loss::Huber(1.0).is_downweighted(0.99));
        assert!(!Loss::Linear.is_downweighted(1e9));
    }
}
