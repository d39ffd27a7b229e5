//! Which parameter combinations the measurements determine: the SVD of the weighted,
//! column-scaled Jacobian, its rank and condition number, and each (near-)null direction named
//! by the parameters it moves.
//!
//! Columns are scaled to unit norm first, so the singular values compare parameters of any units
//! (a parameter no measurement depends on has a zero column and stays zero). The rank counts the
//! singular values above the tolerance, by default σ_max·max(m, n)·ε (LAPACK's and numpy's
//! `matrix_rank` rule: exact rank deficiency up to round-off); pass `rcond` to call directions
//! with σ/σ_max ≤ rcond weakly identifiable too.

use crate::error::{check_finite, check_len, SolverError};
use nalgebra::DMatrix;

/// One combination the measurements do not (or barely) determine.
#[derive(Debug, Clone, PartialEq)]
pub struct NullDirection {
    /// Singular value of the column-scaled Jacobian along it (0 for an exact null direction
    /// in exact arithmetic).
    pub singular_value: f64,
    /// The step δ in parameter units along which the residuals do not change (to first order),
    /// scaled so that its leading parameter's coefficient is 1.
    pub coefficients: Vec<f64>,
    /// The same direction in column-scaled units (used to decide which parameters take part).
    pub scaled: Vec<f64>,
}

/// The SVD analysis of a weighted Jacobian.
#[derive(Debug, Clone, PartialEq)]
pub struct Identifiability {
    pub labels: Vec<String>,
    /// Column norms of the weighted Jacobian (the scaling applied).
    pub column_norms: Vec<f64>,
    /// Singular values of the column-scaled Jacobian, largest first (n of them).
    pub singular_values: Vec<f64>,
    /// Absolute threshold on the scaled singular values used for the rank.
    pub tolerance: f64,
    pub rank: usize,
    /// σ_max/σ_min of the column-scaled Jacobian (∞ when rank-deficient to round-off).
    pub condition_number: f64,
    /// A basis of the directions with σ ≤ tolerance, in reduced row-echelon form (each has one
    /// leading parameter that appears in no other direction), so that they read one at a time.
    pub null_directions: Vec<NullDirection>,
}

/// A scaled coefficient below this share of a direction's largest one is left out of its words.
const NEGLIGIBLE: f64 = 1e-3;

impl Identifiability {
    /// Analyses the (already weighted) m × n Jacobian `j` with parameter `labels`. `rcond`: a
    /// relative tolerance σ/σ_max replacing the default σ_max·max(m, n)·ε.
    pub fn analyze(j: &DMatrix<f64>, labels: &[&str], rcond: Option<f64>) -> Result<Self, SolverError> {
        let (m, n) = j.shape();
        check_len("parameter labels", n, labels.len())?;
        check_finite("Jacobian", j.as_slice())?;
        if let Some(r) = rcond {
            if !(r.is_finite() && r > 0.0 && r < 1.0) {
                return Err(SolverError::Invalid { what: "rcond".into(), reason: format!("must lie in (0, 1), got {r}") });
            }
        }
        if n == 0 || m == 0 {
            // nothing to analyse (no free parameter, or no measurement): every parameter given is
            // unidentifiable, and an SVD of an empty matrix is not defined
            let null_directions = (0..n).map(|k| NullDirection { singular_value: 0.0, coefficients: (0..n).map(|i| if i == k { 1.0 } else { 0.0 }).collect(), scaled: (0..n).map(|i| if i == k { 1.0 } else { 0.0 }).collect() }).collect();
            return Ok(Identifiability { labels: labels.iter().map(|s| s.to_string()).collect(), column_norms: vec![0.0; n], singular_values: vec![0.0; n], tolerance: 0.0, rank: 0, condition_number: if n == 0 { 1.0 } else { f64::INFINITY }, null_directions });
        }
        let column_norms: Vec<f64> = j.column_iter().map(|c| c.norm()).collect();
        // Zero-padded to at least n rows so that V is complete when m < n.
        let mut scaled = DMatrix::zeros(m.max(n), n);
        for k in 0..n {
            let c = if column_norms[k] > 0.0 { column_norms[k] } else { 1.0 };
            for i in 0..m {
                scaled[(i, k)] = j[(i, k)] / c;
            }
        }
        let svd = scaled.svd(false, true);
        let v_t = svd.v_t.ok_or_else(|| SolverError::Invalid { what: "Jacobian".into(), reason: "SVD did not converge".into() })?;
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        let singular_values: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
        let s_max = singular_values.first().copied().unwrap_or(0.0);
        let tolerance = match rcond {
            Some(r) => r * s_max,
            None => s_max * (m.max(n) as f64) * f64::EPSILON,
        };
        let rank = singular_values.iter().filter(|&&s| s > tolerance).count();
        let s_min = singular_values.last().copied().unwrap_or(0.0);
        let condition_number = if s_min > 0.0 { s_max / s_min } else { f64::INFINITY };
        let null: Vec<(f64, Vec<f64>)> = order
            .iter()
            .filter(|&&i| svd.singular_values[i] <= tolerance)
            .map(|&i| (svd.singular_values[i], v_t.row(i).iter().copied().collect()))
            .collect();
        let null_directions = echelon(&null)
            .into_iter()
            .map(|(singular_value, scaled)| {
                let mut coefficients: Vec<f64> = (0..n)
                    .map(|k| scaled[k] / if column_norms[k] > 0.0 { column_norms[k] } else { 1.0 })
                    .collect();
                let lead = leading(&scaled);
                let c0 = coefficients[lead];
                coefficients.iter_mut().for_each(|c| *c /= c0);
                NullDirection { singular_value, coefficients, scaled }
            })
            .collect();
        Ok(Identifiability {
            labels: labels.iter().map(|s| s.to_string()).collect(),
            column_norms,
            singular_values,
            tolerance,
            rank,
            condition_number,
            null_directions,
        })
    }

    /// One sentence per null direction, e.g. "a and b are not separable: a − 0.71·b" (moving the
    /// parameters by δa = 1, δb = −0.71 leaves every residual unchanged), or "c is not
    /// identifiable: no measurement depends on it".
    pub fn describe(&self) -> Vec<String> {
        self.null_directions.iter().map(|d| self.describe_direction(d)).collect()
    }

    fn describe_direction(&self, d: &NullDirection) -> String {
        let max = d.scaled.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut terms: Vec<usize> = (0..d.scaled.len()).filter(|&k| d.scaled[k].abs() > NEGLIGIBLE * max).collect();
        let lead = leading(&d.scaled);
        terms.sort_by_key(|&k| (k != lead, k));
        if terms.len() == 1 {
            return format!("{} is not identifiable: no measurement depends on it", self.labels[terms[0]]);
        }
        let names: Vec<&str> = terms.iter().map(|&k| self.labels[k].as_str()).collect();
        let list = match names.split_last() {
            Some((last, rest)) => format!("{} and {}", rest.join(", "), last),
            None => String::new(),
        };
        let mut combo = String::new();
        for (i, &k) in terms.iter().enumerate() {
            let c = d.coefficients[k];
            let sign = if c < 0.0 { "−" } else { "+" };
            let mag = c.abs();
            let value = if (mag - 1.0).abs() < 5e-3 { String::new() } else { format!("{}·", significant(mag, 2)) };
            if i == 0 {
                combo += &format!("{}{}{}", if c < 0.0 { "−" } else { "" }, value, self.labels[k]);
            } else {
                combo += &format!(" {sign} {value}{}", self.labels[k]);
            }
        }
        format!("{list} are not separable: {combo}")
    }
}

/// Whether |a| beats |b| as a pivot: larger beyond round-off (ties go to the earlier parameter,
/// so that equal shares read in the labels' order).
fn beats(a: f64, b: f64) -> bool {
    a.abs() > b.abs() * (1.0 + 1e-9)
}

/// Index of the largest |v| (the first of equals).
fn leading(v: &[f64]) -> usize {
    (0..v.len()).fold(0, |best, k| if beats(v[k], v[best]) { k } else { best })
}

/// `x` with `digits` significant digits, without trailing zeros ("0.71", "1200", "3.5e-7").
fn significant(x: f64, digits: usize) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    if !(-4..6).contains(&e) {
        return format!("{:.*e}", digits.saturating_sub(1), x);
    }
    let decimals = digits as i32 - 1 - e;
    if decimals < 0 {
        let unit = 10f64.powi(-decimals);
        return format!("{}", (x / unit).round() * unit);
    }
    let s = format!("{:.*}", decimals as usize, x);
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// Reduced row-echelon form of the null basis (rows), pivoting on the largest entry, so each
/// direction has its own leading parameter; each keeps the largest singular value it mixes.
fn echelon(rows: &[(f64, Vec<f64>)]) -> Vec<(f64, Vec<f64>)> {
    let mut b: Vec<(f64, Vec<f64>)> = rows.to_vec();
    let k = b.len();
    let mut used = vec![false; b.first().map_or(0, |r| r.1.len())];
    for i in 0..k {
        // Pivot: largest remaining entry among rows i.. and unused columns.
        let mut best = (i, 0, 0.0f64);
        for (r, row) in b.iter().enumerate().skip(i) {
            for (c, v) in row.1.iter().enumerate() {
                if !used[c] && (beats(*v, best.2) || (best.2 == 0.0 && *v != 0.0)) {
                    best = (r, c, v.abs());
                }
            }
        }
        let (r, c, p) = best;
        if p == 0.0 {
            break;
        }
        b.swap(i, r);
        used[c] = true;
        let pivot = b[i].1[c];
        b[i].1.iter_mut().for_each(|v| *v /= pivot);
        for o in 0..k {
            if o != i {
                let f = b[o].1[c];
                if f != 0.0 {
                    let (src, s_i) = (b[i].1.clone(), b[i].0);
                    b[o].1.iter_mut().zip(&src).for_each(|(v, s)| *v -= f * s);
                    b[o].0 = b[o].0.max(s_i);
                }
            }
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits() {
        assert_eq!(significant(0.7071, 2), "0.71");
        assert_eq!(significant(1234.0, 2), "1200");
        assert_eq!(significant(2.0, 2), "2");
        assert_eq!(significant(3.5e-7, 2), "3.5e-7");
    }
}
