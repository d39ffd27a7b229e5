//! Error functions of one axis over its travel: a polynomial or Legendre series in the
//! normalised coordinate u = 2·(q − q_min)/(q_max − q_min) − 1 ∈ [−1, 1].
//! Coefficients therefore all carry the unit of the error (m for translations, rad for
//! rotations), whatever the order — which keeps one unit per parameter in the catalog.
//! Legendre (default) keeps the coefficients nearly uncorrelated over the travel.

use crate::config::Options;
use crate::error::PhysicsError;

/// Basis of an error series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesBasis {
    /// φ_i(u) = u^i.
    Polynomial,
    /// φ_i(u) = P_i(u), Legendre polynomials.
    Legendre,
}

/// Highest series order a config may ask for.
pub const MAX_ORDER: usize = 8;

/// Shape of an error series: basis, order and travel (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorSeries {
    pub basis: SeriesBasis,
    pub order: usize,
    pub travel: (f64, f64),
}

impl ErrorSeries {
    pub fn new(basis: SeriesBasis, order: usize, travel: (f64, f64)) -> Result<Self, PhysicsError> {
        if !(travel.1 > travel.0) || !travel.0.is_finite() || !travel.1.is_finite() {
            return Err(PhysicsError::InvalidInput {
                what: "error series travel".into(),
                reason: format!("needs min < max, got [{}, {}]", travel.0, travel.1),
            });
        }
        Ok(Self {
            basis,
            order,
            travel,
        })
    }

    /// Read `basis` (legendre|polynomial, default legendre), `order` (default `default_order`)
    /// and `travel` ([min, max] in m, default [0, 1] m) from options.
    pub fn from_options(o: &Options, default_order: usize) -> Result<Self, PhysicsError> {
        let basis = match o.text("basis", Some("legendre"))?.as_str() {
            "legendre" => SeriesBasis::Legendre,
            "polynomial" => SeriesBasis::Polynomial,
            other => {
                return Err(o.bad(
                    "basis",
                    format!("`{other}` is not a basis; allowed: legendre, polynomial"),
                ))
            }
        };
        let order = o.count("order", default_order, MAX_ORDER)?;
        let travel = o.length_range("travel")?.unwrap_or((0.0, 1.0));
        Self::new(basis, order, travel).map_err(|e| o.bad("travel", e.to_string()))
    }

    /// Number of coefficients (order + 1).
    #[allow(clippy::len_without_is_empty)] // never empty: order 0 has one coefficient
    pub fn len(&self) -> usize {
        self.order + 1
    }

    pub fn normalised(&self, q: f64) -> f64 {
        2.0 * (q - self.travel.0) / (self.travel.1 - self.travel.0) - 1.0
    }

    /// Basis values φ_0..φ_order at axis position q (also the Jacobian row of the series), in
    /// the first [`Self::len`] entries, without allocating.
    pub fn basis_array(&self, q: f64) -> [f64; MAX_ORDER + 1] {
        let u = self.normalised(q);
        let mut out = [0.0; MAX_ORDER + 1];
        let n = self.len().min(MAX_ORDER + 1);
        match self.basis {
            SeriesBasis::Polynomial => {
                let mut v = 1.0;
                for o in out.iter_mut().take(n) {
                    *o = v;
                    v *= u;
                }
            }
            SeriesBasis::Legendre => {
                out[0] = 1.0;
                if n >= 2 {
                    out[1] = u;
                }
                for k in 1..n - 1 {
                    let kf = k as f64;
                    out[k + 1] = ((2.0 * kf + 1.0) * u * out[k] - kf * out[k - 1]) / (kf + 1.0);
                }
            }
        }
        out
    }

    /// Basis values φ_0..φ_order at axis position q (also the Jacobian row of the series).
    pub fn basis_values(&self, q: f64) -> Vec<f64> {
        self.basis_array(q)[..self.len()].to_vec()
    }

    /// Value of the series with coefficients `c` at q.
    pub fn eval(&self, c: &[f64], q: f64) -> f64 {
        self.combine(&self.basis_array(q), c)
    }

    /// Value of the series with coefficients `c` from its basis values at q
    /// ([`Self::basis_array`]): [`Self::eval`] bit for bit, for a caller that needs the basis
    /// (the Jacobian row) too and computes it once.
    pub fn combine(&self, basis: &[f64; MAX_ORDER + 1], c: &[f64]) -> f64 {
        basis[..self.len()].iter().zip(c).map(|(b, c)| b * c).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn legendre_values() {
        let s = ErrorSeries::new(SeriesBasis::Legendre, 3, (0.0, 2.0)).unwrap();
        // q = 1.5 → u = 0.5; P2 = (3u²−1)/2 = −0.125, P3 = (5u³−3u)/2 = −0.4375
        let b = s.basis_values(1.5);
        assert!((b[2] + 0.125).abs() < 1e-15 && (b[3] + 0.4375).abs() < 1e-15);
    }
}
