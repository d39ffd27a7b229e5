//! Which parameter combinations the measurements determine: the SVD of the weighted,
//! column-scaled Jacobian, its rank and condition number, and each (near-)null direction named
//! by the parameters it moves.
//!
//! Columns are scaled to unit norm first, so the singular values compare parameters of any units
//! (a parameter no measurement depends on has a zero column and stays zero). The rank counts the
//! singular values above the tolerance, by default σ_max·max(m, n)·ε (LAPACK's and numpy's
//! `matrix_rank` rule: exact rank deficiency up to round-off); pass `rcond` to call directions
//! with σ/σ_max ≤ rcond weakly identifiable too.
//!
//! Two ways to the same singular values. With the default tolerance (round-off) only the SVD of
//! the m × n matrix resolves them. With `rcond` ≥ [`GRAM_RCOND`] the eigen-decomposition of the
//! column-scaled Gram matrix JᵀJ (n × n, formed by a blocked product) is used instead: its
//! eigenvalues λ = σ² carry an absolute error of order n·ε·λ_max, so σ is resolved down to
//! √(n·ε)·σ_max ≈ 1e-7·σ_max for n = 75, about eight times below a tolerance of 1e-6, the one `fit`
//! uses and the one below which the covariance (crates/solver `free_inverse`) calls the normal
//! matrix singular. On the 30 000 × 46 Jacobian of BENCHMARKS.md's batch fit the SVD was a quarter
//! of the whole fit's time; the Gram route no longer shows in its profile. Singular values
//! below that resolution are reported as 0 (exact null directions as far as this computation can
//! tell), so the condition number is then ∞ as it is for an exactly rank-deficient SVD.

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

/// The smallest `rcond` for which the Gram route is taken (see the module docs).
pub const GRAM_RCOND: f64 = 1e-6;

/// A scaled coefficient below this share of a direction's largest one is left out of its words.
const NEGLIGIBLE: f64 = 1e-3;

impl Identifiability {
    /// Analyses the (already weighted) m × n Jacobian `j` with parameter `labels`. `rcond`: a
    /// relative tolerance σ/σ_max replacing the default σ_max·max(m, n)·ε.
    pub fn analyze(
        j: &DMatrix<f64>,
        labels: &[&str],
        rcond: Option<f64>,
    ) -> Result<Self, SolverError> {
        let (m, n) = j.shape();
        check_len("parameter labels", n, labels.len())?;
        check_finite("Jacobian", j.as_slice())?;
        if let Some(r) = rcond {
            if !(r.is_finite() && r > 0.0 && r < 1.0) {
                return Err(SolverError::Invalid {
                    what: "rcond".into(),
                    reason: format!("must lie in (0, 1), got {r}"),
                });
            }
        }
        if n == 0 || m == 0 {
            return Ok(Self::nothing_determined(labels));
        }
        let column_norms: Vec<f64> = j.column_iter().map(|c| c.norm()).collect();
        let pairs = if rcond.is_some_and(|r| r >= GRAM_RCOND) {
            let all: Vec<usize> = (0..n).collect();
            gram_pairs(&crate::normal_matrix(j, &all), &column_norms)
        } else {
            svd_pairs(j, &column_norms)?
        };
        Ok(Self::from_pairs(pairs, column_norms, labels, m, rcond))
    }

    /// [`Identifiability::analyze`] from the normal matrix JᵀJ (n × n) of the weighted Jacobian
    /// instead of J, for a caller that has formed it already (the solver, every iteration): the
    /// Gram route, so `rcond` must be at least [`GRAM_RCOND`]. `m` is J's row count (0: no
    /// measurement).
    pub fn from_normal_matrix(
        normal: &DMatrix<f64>,
        m: usize,
        labels: &[&str],
        rcond: f64,
    ) -> Result<Self, SolverError> {
        let n = normal.nrows();
        check_len("parameter labels", n, labels.len())?;
        check_finite("normal matrix", normal.as_slice())?;
        if !(GRAM_RCOND..1.0).contains(&rcond) {
            return Err(SolverError::Invalid { what: "rcond".into(), reason: format!("the normal matrix resolves singular values down to ~1e-7 of the largest: rcond must lie in [{GRAM_RCOND}, 1), got {rcond} (use Identifiability::analyze on the Jacobian)") });
        }
        if n == 0 || m == 0 {
            return Ok(Self::nothing_determined(labels));
        }
        let column_norms: Vec<f64> = (0..n).map(|k| normal[(k, k)].max(0.0).sqrt()).collect();
        Ok(Self::from_pairs(
            gram_pairs(normal, &column_norms),
            column_norms,
            labels,
            m,
            Some(rcond),
        ))
    }

    /// Every parameter unidentifiable: no free parameter or no measurement (an SVD of an empty
    /// matrix is not defined).
    fn nothing_determined(labels: &[&str]) -> Self {
        let n = labels.len();
        let unit = |k: usize| {
            (0..n)
                .map(|i| if i == k { 1.0 } else { 0.0 })
                .collect::<Vec<f64>>()
        };
        let null_directions = (0..n)
            .map(|k| NullDirection {
                singular_value: 0.0,
                coefficients: unit(k),
                scaled: unit(k),
            })
            .collect();
        Identifiability {
            labels: labels.iter().map(|s| s.to_string()).collect(),
            column_norms: vec![0.0; n],
            singular_values: vec![0.0; n],
            tolerance: 0.0,
            rank: 0,
            condition_number: if n == 0 { 1.0 } else { f64::INFINITY },
            null_directions,
        }
    }

    /// The analysis from the (singular value, right singular vector) pairs of the column-scaled
    /// m × n Jacobian.
    fn from_pairs(
        pairs: Vec<(f64, Vec<f64>)>,
        column_norms: Vec<f64>,
        labels: &[&str],
        m: usize,
        rcond: Option<f64>,
    ) -> Self {
        let n = pairs.len();
        let scale = |k: usize| unit_scale(&column_norms, k);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| pairs[b].0.total_cmp(&pairs[a].0));
        let singular_values: Vec<f64> = order.iter().map(|&i| pairs[i].0).collect();
        let s_max = singular_values.first().copied().unwrap_or(0.0);
        let tolerance = match rcond {
            Some(r) => r * s_max,
            None => s_max * (m.max(n) as f64) * f64::EPSILON,
        };
        let rank = singular_values.iter().filter(|&&s| s > tolerance).count();
        let s_min = singular_values.last().copied().unwrap_or(0.0);
        let condition_number = if s_min > 0.0 {
            s_max / s_min
        } else {
            f64::INFINITY
        };
        let null: Vec<(f64, Vec<f64>)> = order
            .iter()
            .filter(|&&i| pairs[i].0 <= tolerance)
            .map(|&i| pairs[i].clone())
            .collect();
        let null_directions = echelon(&null)
            .into_iter()
            .map(|(singular_value, scaled)| {
                let mut coefficients: Vec<f64> = (0..n).map(|k| scaled[k] / scale(k)).collect();
                let lead = leading(&scaled);
                let c0 = coefficients[lead];
                coefficients.iter_mut().for_each(|c| *c /= c0);
                NullDirection {
                    singular_value,
                    coefficients,
                    scaled,
                }
            })
            .collect();
        Identifiability {
            labels: labels.iter().map(|s| s.to_string()).collect(),
            column_norms,
            singular_values,
            tolerance,
            rank,
            condition_number,
            null_directions,
        }
    }

    /// One sentence per null direction, e.g. "a and b are not separable: a − 0.71·b" (moving the
    /// parameters by δa = 1, δb = −0.71 leaves every residual unchanged), or "c is not
    /// identifiable: no measurement depends on it".
    pub fn describe(&self) -> Vec<String> {
        self.null_directions
            .iter()
            .map(|d| self.describe_direction(d))
            .collect()
    }

    fn describe_direction(&self, d: &NullDirection) -> String {
        let max = d.scaled.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut terms: Vec<usize> = (0..d.scaled.len())
            .filter(|&k| d.scaled[k].abs() > NEGLIGIBLE * max)
            .collect();
        let lead = leading(&d.scaled);
        terms.sort_by_key(|&k| (k != lead, k));
        if terms.len() == 1 {
            return format!(
                "{} is not identifiable: no measurement depends on it",
                self.labels[terms[0]]
            );
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
            let value = if (mag - 1.0).abs() < 5e-3 {
                String::new()
            } else {
                format!("{}·", significant(mag, 2))
            };
            if i == 0 {
                combo += &format!(
                    "{}{}{}",
                    if c < 0.0 { "−" } else { "" },
                    value,
                    self.labels[k]
                );
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
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
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

/// The factor column `k` is divided by: its norm, or 1 for a zero column.
fn unit_scale(column_norms: &[f64], k: usize) -> f64 {
    if column_norms[k] > 0.0 {
        column_norms[k]
    } else {
        1.0
    }
}

/// (singular value, right singular vector) of the column-scaled `j`, from its SVD.
fn svd_pairs(j: &DMatrix<f64>, column_norms: &[f64]) -> Result<Vec<(f64, Vec<f64>)>, SolverError> {
    let (m, n) = j.shape();
    // zero-padded to at least n rows so that V is complete when m < n
    let mut scaled = DMatrix::zeros(m.max(n), n);
    for k in 0..n {
        let c = unit_scale(column_norms, k);
        for i in 0..m {
            scaled[(i, k)] = j[(i, k)] / c;
        }
    }
    let svd = scaled.svd(false, true);
    let v_t = svd.v_t.ok_or_else(|| SolverError::Invalid {
        what: "Jacobian".into(),
        reason: "SVD did not converge".into(),
    })?;
    Ok((0..n)
        .map(|i| (svd.singular_values[i], v_t.row(i).iter().copied().collect()))
        .collect())
}

/// The same pairs from the eigen-decomposition of the column-scaled Gram matrix JᵀJ (`gram`),
/// singular values below its resolution √(n·ε)·σ_max set to 0 (see the module docs).
fn gram_pairs(gram: &DMatrix<f64>, column_norms: &[f64]) -> Vec<(f64, Vec<f64>)> {
    let n = gram.ncols();
    let scaled = DMatrix::from_fn(n, n, |a, b| {
        gram[(a, b)] / (unit_scale(column_norms, a) * unit_scale(column_norms, b))
    });
    let eig = scaled.symmetric_eigen();
    let resolution = ((n as f64) * f64::EPSILON).sqrt() * eig.eigenvalues.max().max(0.0).sqrt();
    (0..n)
        .map(|e| {
            let s = eig.eigenvalues[e].max(0.0).sqrt();
            (
                if s > resolution { s } else { 0.0 },
                eig.eigenvectors.column(e).iter().copied().collect(),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::approx_constant)] // a number to round, not 1/√2
    fn significant_digits() {
        assert_eq!(significant(0.7071, 2), "0.71");
        assert_eq!(significant(1234.0, 2), "1200");
        assert_eq!(significant(2.0, 2), "2");
        assert_eq!(significant(3.5e-7, 2), "3.5e-7");
    }

    /// The Gram route gives the SVD's singular values and null space on a badly scaled Jacobian
    /// with one exact dependence and one weak but identifiable pair.
    #[test]
    fn gram_route_agrees_with_the_svd() {
        let (m, n) = (3000, 8);
        let mut state = 12345u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let scales = [1e-6, 1.0, 1e3, 0.2, 5.0, 5.0, 1e2, 1.0];
        let mut j = DMatrix::from_fn(m, n, |_, k| scales[k] * uniform());
        for i in 0..m {
            // column 7 = 2·col1 − 0.5·col3 exactly: a null direction
            j[(i, 7)] = 2.0 * j[(i, 1)] - 0.5 * j[(i, 3)];
            // column 6 nearly column 5: σ/σ_max ≈ 1e-4, weak but above 1e-6
            j[(i, 6)] = j[(i, 5)] + 1e-4 * 5.0 * uniform();
        }
        let norms: Vec<f64> = j.column_iter().map(|c| c.norm()).collect();
        let sorted = |mut p: Vec<(f64, Vec<f64>)>| {
            p.sort_by(|a, b| b.0.total_cmp(&a.0));
            p
        };
        let (svd, gram) = (
            sorted(svd_pairs(&j, &norms).unwrap()),
            sorted(gram_pairs(&(j.transpose() * &j), &norms)),
        );
        let s_max = svd[0].0;
        for (a, b) in svd.iter().zip(&gram) {
            if a.0 > 1e-6 * s_max {
                assert!(
                    (a.0 - b.0).abs() <= 1e-9 * s_max.max(1.0) + 1e-6 * a.0,
                    "σ {} vs {}",
                    a.0,
                    b.0
                );
                let dot: f64 = a.1.iter().zip(&b.1).map(|(x, y)| x * y).sum();
                assert!(
                    dot.abs() > 1.0 - 1e-6,
                    "singular vector of σ {} differs: |cos| {}",
                    a.0,
                    dot.abs()
                );
            }
        }
        assert_eq!(
            gram[n - 1].0,
            0.0,
            "the exact null is below the Gram resolution"
        );
        let labels = ["a", "b", "c", "d", "e", "f", "g", "h"];
        let by_svd = Identifiability::analyze(&j, &labels, Some(0.5 * GRAM_RCOND)).unwrap();
        let by_gram = Identifiability::analyze(&j, &labels, Some(GRAM_RCOND)).unwrap();
        assert_eq!((by_svd.rank, by_gram.rank), (7, 7));
        assert_eq!(by_gram.describe(), by_svd.describe());
        // the same from the normal matrix the solver forms
        let from_normal = Identifiability::from_normal_matrix(
            &crate::normal_matrix(&j, &(0..n).collect::<Vec<_>>()),
            m,
            &labels,
            GRAM_RCOND,
        )
        .unwrap();
        assert_eq!(
            (from_normal.rank, from_normal.describe()),
            (by_gram.rank, by_gram.describe())
        );
        assert!(
            Identifiability::from_normal_matrix(
                &(j.transpose() * &j),
                m,
                &labels,
                0.5 * GRAM_RCOND
            )
            .is_err(),
            "below the Gram route's resolution"
        );
        let c = &by_gram.null_directions[0].coefficients;
        // the direction δh = 1, δb = −2, δd = 0.5 leaves every residual unchanged
        assert!(
            (c[7] - 1.0).abs() < 1e-9 && (c[1] + 2.0).abs() < 1e-9 && (c[3] - 0.5).abs() < 1e-9,
            "{c:?}"
        );
    }
}
