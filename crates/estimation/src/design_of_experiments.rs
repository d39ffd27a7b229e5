//! Which measurements to make: a D-optimal choice of `rows` rows from a candidate Jacobian.
//!
//! Each candidate row is one measurement (a position and a measured direction, seed 000 §4) and
//! its sensitivity to the model's parameters. A design X (the chosen rows) is D-optimal when it
//! maximises det(XᵀX): the volume of the parameters' confidence ellipsoid is then smallest.
//! Seed 000 uses DETMAX (Mitchell 1974); this is the Fedorov exchange of the same family: start
//! from a greedy design, then repeatedly swap the design row and candidate row whose exchange
//! multiplies the determinant most, det(M′) = det(M)·(1 + Δ) with
//! Δ = d(j) − d(i) − d(i)·d(j) + d(i,j)², d(a,b) = x_aᵀ M⁻¹ x_b, until no swap gains.
//! Several seeded random restarts guard against a local optimum; the best design is kept.
//!
//! With fewer rows than parameters, or parameters the candidates cannot separate, XᵀX is
//! singular; the criterion is then det(XᵀX + εI) with ε = 1e-9 of the mean diagonal, so designs
//! are still ranked by how much they pin down the identifiable part, and the rank is reported.

use nalgebra::{DMatrix, DVector};
use rand::seq::index::sample;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A chosen design.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Indices of the chosen candidate rows, ascending.
    pub rows: Vec<usize>,
    /// ln det(XᵀX + εI) of the chosen rows (columns as given).
    pub log_det: f64,
    /// Numerical rank of XᵀX.
    pub rank: usize,
    /// Exchanges made by the winning restart.
    pub exchanges: usize,
}

/// Why no design could be chosen.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DesignError {
    #[error("cannot choose {wanted} rows from {available} candidates")]
    TooFewCandidates { wanted: usize, available: usize },
    #[error("candidate row {row} holds a value that is not finite")]
    NotFinite { row: usize },
    #[error("the candidates carry no information (every row is zero)")]
    Empty,
}

/// ln det(XᵀX + εI) of the rows `chosen` of `candidates`, the ridge ε as in the module docs.
pub fn log_det(candidates: &DMatrix<f64>, chosen: &[usize], ridge: f64) -> f64 {
    let m = information(candidates, chosen, ridge);
    match m.cholesky() {
        Some(c) => 2.0 * c.l().diagonal().iter().map(|d| d.ln()).sum::<f64>(),
        None => f64::NEG_INFINITY,
    }
}

fn information(candidates: &DMatrix<f64>, chosen: &[usize], ridge: f64) -> DMatrix<f64> {
    let p = candidates.ncols();
    let mut m = DMatrix::<f64>::identity(p, p) * ridge;
    for &i in chosen {
        let r = candidates.row(i);
        m += r.transpose() * r;
    }
    m
}

/// The ridge ε for these candidates.
pub fn ridge_for(candidates: &DMatrix<f64>) -> f64 {
    let p = candidates.ncols().max(1) as f64;
    let mean_diag = candidates.iter().map(|x| x * x).sum::<f64>() / p;
    1e-9 * mean_diag.max(f64::MIN_POSITIVE)
}

/// The largest ln det(XᵀX + εI) among `trials` random `rows`-row designs (seeded): the yardstick
/// a chosen design is judged against.
pub fn best_random_log_det(
    candidates: &DMatrix<f64>,
    rows: usize,
    trials: usize,
    seed: u64,
) -> f64 {
    let (n, ridge) = (candidates.nrows(), ridge_for(candidates));
    if rows == 0 || rows > n {
        return f64::NEG_INFINITY;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..trials)
        .map(|_| log_det(candidates, &sample(&mut rng, n, rows).into_vec(), ridge))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Choose `rows` rows of `candidates` (N × p) maximising det(XᵀX), with `restarts` seeded random
/// restarts besides the greedy start.
pub fn d_optimal(
    candidates: &DMatrix<f64>,
    rows: usize,
    restarts: usize,
    seed: u64,
) -> Result<Design, DesignError> {
    let n = candidates.nrows();
    if rows > n || rows == 0 {
        return Err(DesignError::TooFewCandidates {
            wanted: rows,
            available: n,
        });
    }
    if let Some(row) = (0..n).find(|&i| candidates.row(i).iter().any(|x| !x.is_finite())) {
        return Err(DesignError::NotFinite { row });
    }
    if candidates.iter().all(|x| *x == 0.0) {
        return Err(DesignError::Empty);
    }
    let ridge = ridge_for(candidates);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut best: Option<Design> = None;
    for start in 0..=restarts {
        let initial = if start == 0 {
            greedy(candidates, rows, ridge)
        } else {
            sample(&mut rng, n, rows).into_vec()
        };
        let (chosen, exchanges) = exchange(candidates, initial, ridge);
        let ld = log_det(candidates, &chosen, ridge);
        if best.as_ref().is_none_or(|b| ld > b.log_det + 1e-12) {
            let mut sorted = chosen;
            sorted.sort_unstable();
            // singular values of XᵀX below the ridge are what the ridge alone holds up
            let rank = information(candidates, &sorted, 0.0)
                .svd(false, false)
                .rank(ridge);
            best = Some(Design {
                rows: sorted,
                log_det: ld,
                rank,
                exchanges,
            });
        }
    }
    Ok(best.expect("at least the greedy start runs"))
}

/// Add one row at a time, each the candidate with the largest prediction variance d(x).
fn greedy(candidates: &DMatrix<f64>, rows: usize, ridge: f64) -> Vec<usize> {
    let mut chosen: Vec<usize> = Vec::with_capacity(rows);
    while chosen.len() < rows {
        let minv = information(candidates, &chosen, ridge)
            .try_inverse()
            .expect("ridge makes the information invertible");
        let next = (0..candidates.nrows())
            .filter(|i| !chosen.contains(i))
            .map(|i| {
                let x: DVector<f64> = candidates.row(i).transpose();
                (i, (x.transpose() * &minv * &x)[0])
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
            .expect("rows ≤ candidates");
        chosen.push(next);
    }
    chosen
}

/// Fedorov exchange from `chosen` until no swap multiplies the determinant by more than 1 + 1e-10.
fn exchange(candidates: &DMatrix<f64>, mut chosen: Vec<usize>, ridge: f64) -> (Vec<usize>, usize) {
    let n = candidates.nrows();
    let max_exchanges = 100 * chosen.len().max(1);
    let mut exchanges = 0;
    while exchanges < max_exchanges {
        let minv = information(candidates, &chosen, ridge)
            .try_inverse()
            .expect("ridge makes the information invertible");
        // V = X_cand·M⁻¹: d(a, b) = V_a · x_b
        let v = candidates * &minv;
        let d = |a: usize, b: usize| v.row(a).dot(&candidates.row(b));
        let in_design: Vec<bool> = (0..n).map(|i| chosen.contains(&i)).collect();
        let mut best = (1e-10, usize::MAX, usize::MAX);
        for (slot, &i) in chosen.iter().enumerate() {
            let di = d(i, i);
            for j in (0..n).filter(|&j| !in_design[j]) {
                let dj = d(j, j);
                let dij = d(i, j);
                let delta = dj - di - di * dj + dij * dij;
                if delta > best.0 {
                    best = (delta, slot, j);
                }
            }
        }
        if best.1 == usize::MAX {
            break;
        }
        chosen[best.1] = best.2;
        exchanges += 1;
    }
    (chosen, exchanges)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polynomial_candidates(order: usize, grid: usize) -> (DMatrix<f64>, Vec<f64>) {
        let xs: Vec<f64> = (0..grid)
            .map(|i| -1.0 + 2.0 * i as f64 / (grid - 1) as f64)
            .collect();
        (
            DMatrix::from_fn(grid, order + 1, |i, k| xs[i].powi(k as i32)),
            xs,
        )
    }

    /// Known D-optimal designs on [−1, 1]: a line at the two ends, a parabola at −1, 0, 1.
    #[test]
    fn textbook_designs() {
        let (c, xs) = polynomial_candidates(1, 21);
        let d = d_optimal(&c, 2, 3, 1).unwrap();
        assert_eq!(
            d.rows.iter().map(|&i| xs[i]).collect::<Vec<_>>(),
            vec![-1.0, 1.0]
        );
        let (c, xs) = polynomial_candidates(2, 21);
        let d = d_optimal(&c, 3, 3, 1).unwrap();
        assert_eq!(
            d.rows.iter().map(|&i| xs[i]).collect::<Vec<_>>(),
            vec![-1.0, 0.0, 1.0]
        );
        assert_eq!(d.rank, 3);
    }

    #[test]
    fn bad_candidates_are_errors() {
        let (c, _) = polynomial_candidates(1, 5);
        assert!(matches!(
            d_optimal(&c, 6, 0, 1),
            Err(DesignError::TooFewCandidates { .. })
        ));
        let mut bad = c.clone();
        bad[(3, 1)] = f64::NAN;
        assert_eq!(
            d_optimal(&bad, 2, 0, 1),
            Err(DesignError::NotFinite { row: 3 })
        );
        assert_eq!(
            d_optimal(&DMatrix::zeros(4, 2), 2, 0, 1),
            Err(DesignError::Empty)
        );
    }
}
