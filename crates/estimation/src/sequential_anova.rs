//! Analysis of variance with sequential (type I) sums of squares: each term's SS is how much the
//! residual sum of squares falls when it joins the least-squares model after the terms before it
//! (an intercept is always first). This is the table a design-of-experiments package prints
//! for a regression model, and what seed 000's Tables 6 and 7 (image type A, inclination B, AB,
//! B²) report for its camera experiment.
//!
//! With an unbalanced design (seed 000's Table 5 has 3 to 5 runs per cell) the order matters:
//! a term entered first takes the variation it shares with later ones. Its F is MS_term /
//! MS_error of the full model, its p the F distribution's upper tail. A term whose columns add
//! nothing new (collinear with earlier ones) gets 0 degrees of freedom and no F.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// One row of the table: a term of the model.
#[derive(Debug, Clone, PartialEq)]
pub struct AnovaRow {
    pub name: String,
    pub sum_of_squares: f64,
    /// Columns the term adds to the model's rank.
    pub degrees_of_freedom: usize,
    pub mean_square: f64,
    /// None when the term adds no degree of freedom or the error has none.
    pub f: Option<f64>,
    pub p: Option<f64>,
}

/// The whole table.
#[derive(Debug, Clone, PartialEq)]
pub struct AnovaTable {
    pub terms: Vec<AnovaRow>,
    pub error_sum_of_squares: f64,
    pub error_degrees_of_freedom: usize,
    /// Corrected total: Σ(y − ȳ)².
    pub total_sum_of_squares: f64,
    pub total_degrees_of_freedom: usize,
}

/// Why a table cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnovaError {
    #[error("term `{term}` has {got} values for {n} observations")]
    Length { term: String, got: usize, n: usize },
    #[error("{what} is not finite")]
    NotFinite { what: String },
    #[error("{n} observations cannot be split among an intercept and {columns} columns")]
    TooFewObservations { n: usize, columns: usize },
}

/// Sequential ANOVA of `y` on `terms` (name, column), entered in the order given after an
/// intercept.
pub fn sequential_anova(y: &[f64], terms: &[(&str, Vec<f64>)]) -> Result<AnovaTable, AnovaError> {
    let n = y.len();
    check(y, "the response")?;
    for (name, column) in terms {
        if column.len() != n {
            return Err(AnovaError::Length {
                term: name.to_string(),
                got: column.len(),
                n,
            });
        }
        check(column, &format!("term `{name}`"))?;
    }
    if n < terms.len() + 2 {
        return Err(AnovaError::TooFewObservations {
            n,
            columns: terms.len(),
        });
    }
    let mut columns: Vec<Vec<f64>> = vec![vec![1.0; n]];
    let (mut rss, mut rank) = residual_sum_of_squares(y, &columns);
    let total = rss;
    let mut rows = Vec::with_capacity(terms.len());
    for (name, column) in terms {
        columns.push(column.clone());
        let (next_rss, next_rank) = residual_sum_of_squares(y, &columns);
        let df = next_rank - rank;
        let ss = if df == 0 {
            0.0
        } else {
            (rss - next_rss).max(0.0)
        };
        rows.push(AnovaRow {
            name: name.to_string(),
            sum_of_squares: ss,
            degrees_of_freedom: df,
            mean_square: if df == 0 { 0.0 } else { ss / df as f64 },
            f: None,
            p: None,
        });
        (rss, rank) = (next_rss, next_rank);
    }
    let error_df = n - rank;
    if error_df > 0 {
        let error_ms = rss / error_df as f64;
        for row in rows.iter_mut().filter(|r| r.degrees_of_freedom > 0) {
            let f = row.mean_square / error_ms;
            row.f = Some(f);
            row.p = FisherSnedecor::new(row.degrees_of_freedom as f64, error_df as f64)
                .ok()
                .map(|d| d.sf(f));
        }
    }
    Ok(AnovaTable {
        terms: rows,
        error_sum_of_squares: rss,
        error_degrees_of_freedom: error_df,
        total_sum_of_squares: total,
        total_degrees_of_freedom: n - 1,
    })
}

fn check(values: &[f64], what: &str) -> Result<(), AnovaError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(AnovaError::NotFinite {
            what: format!("{what} at observation {}", i + 1),
        }),
        None => Ok(()),
    }
}

/// RSS of the least-squares fit of `y` on `columns`, and the columns' numerical rank (SVD).
fn residual_sum_of_squares(y: &[f64], columns: &[Vec<f64>]) -> (f64, usize) {
    let n = y.len();
    let x = DMatrix::from_fn(n, columns.len(), |i, j| columns[j][i]);
    let svd = x.clone().svd(true, true);
    let largest = svd.singular_values.max();
    let tolerance = largest * n.max(columns.len()) as f64 * f64::EPSILON;
    let rank = svd
        .singular_values
        .iter()
        .filter(|s| **s > tolerance)
        .count();
    let y = DVector::from_column_slice(y);
    let beta = svd.solve(&y, tolerance).expect("U and Vᵀ were computed");
    let residual = &y - &x * beta;
    (residual.norm_squared(), rank)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balanced_one_way_layout_matches_the_hand_sums() {
        // two groups of three: means 2 and 5, grand mean 3.5
        let y = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let group = vec![-1.0, -1.0, -1.0, 1.0, 1.0, 1.0];
        let t = sequential_anova(&y, &[("group", group)]).unwrap();
        assert!((t.total_sum_of_squares - 17.5).abs() < 1e-12);
        assert!((t.terms[0].sum_of_squares - 13.5).abs() < 1e-12);
        assert!((t.error_sum_of_squares - 4.0).abs() < 1e-12);
        assert_eq!(
            (t.terms[0].degrees_of_freedom, t.error_degrees_of_freedom),
            (1, 4)
        );
        assert!((t.terms[0].f.unwrap() - 13.5).abs() < 1e-12);
        // F(1, 4) = 13.5 ↔ p = 0.02131 (t = √13.5 with 4 dof)
        assert!((t.terms[0].p.unwrap() - 0.021312).abs() < 1e-5);
    }

    #[test]
    fn a_collinear_term_adds_nothing() {
        let y = [1.0, 2.0, 4.0, 3.0, 6.0];
        let x = vec![0.0, 1.0, 2.0, 3.0, 4.0];
        let twice: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        let t = sequential_anova(&y, &[("x", x), ("2x", twice)]).unwrap();
        assert_eq!(t.terms[1].degrees_of_freedom, 0);
        assert_eq!(t.terms[1].sum_of_squares, 0.0);
        assert_eq!(t.terms[1].f, None);
        assert_eq!(t.error_degrees_of_freedom, 3);
    }

    #[test]
    fn bad_input_is_named() {
        let e = sequential_anova(&[1.0, f64::NAN, 2.0, 3.0], &[("a", vec![0.0; 4])]).unwrap_err();
        assert_eq!(e.to_string(), "the response at observation 2 is not finite");
        let e = sequential_anova(&[1.0, 2.0, 3.0], &[("a", vec![0.0; 2])]).unwrap_err();
        assert_eq!(e.to_string(), "term `a` has 2 values for 3 observations");
    }
}
