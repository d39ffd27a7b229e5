//! Parameter uncertainties that stay honest when the residuals are correlated in time.
//!
//! The least-squares covariance σ̂₀²·(AᵀA)⁻¹ assumes independent rows. A recording's residuals
//! are not: whatever the model does not hold and no candidate took out (an air or temperature
//! drift, a tracker's slow wander, sub-µm structure left as unexplained) moves neighbouring
//! measurements together, and averaging the repeats of a dwell shrinks the white part of the
//! noise while leaving the correlated part whole. Then σ̂₀² still measures the residuals' size
//! but (AᵀA)⁻¹ counts every record as new information, and σ comes out too small by
//! roughly the square root of the number of records one correlation time spans.
//!
//! The remedy is the sandwich (heteroscedasticity- and autocorrelation-consistent, HAC)
//! covariance P·S·P with P = (AᵀA)⁺ and S the long-run covariance of the scores gᵢ = Aᵢᵀeᵢ
//! (record i's whitened columns times its residuals): the scores are summed over
//! [`BLOCKS`] consecutive blocks of time (correlation inside a block counted in full), and the
//! block sums combined by Newey–West (Bartlett weights) over as many neighbouring blocks as
//! Andrews' AR(1) plug-in rule asks for (more when the scores stay correlated from block to
//! block). Each parameter's σ is the larger of the sandwich and the independent-rows figure:
//! the sandwich's own estimate scatters (and Bartlett weights understate long correlation), so
//! it only ever widens an uncertainty. The same sandwich with the scores clustered by place
//! ([`by_place`]) sees static structure the model lacks, which repeats wherever the program
//! returns. Cost: O(records · parameters²), well under the selection's.
//!
//! A bias no covariance shows — a term the data support that the selection declined, part of
//! whose effect a found term absorbs — is counted by the pipeline from [`shift_if_added`].

use nalgebra::{DMatrix, DVector};

use crate::folds::time_blocks;

/// Consecutive blocks of time the scores are summed over: enough that the long-run covariance
/// has a few hundred degrees of freedom, few enough that each block spans several records.
pub const BLOCKS: usize = 200;

/// The sandwich covariance and what it found.
#[derive(Debug, Clone)]
pub struct SerialCovariance {
    /// P·S·P, scaled for the degrees of freedom (rows / (rows − rank)).
    pub covariance: DMatrix<f64>,
    /// Blocks of time the scores were summed over.
    pub blocks: usize,
    /// Neighbouring blocks whose covariance was counted (Bartlett lag window).
    pub lag_blocks: usize,
}

/// The sandwich covariance of the least-squares solution with whitened columns `a` (3 rows per
/// record, records in any order), whitened residuals `e` at the solution, `bread` = (AᵀA)⁺ and
/// `times` one per record; `rank` of the fit. None with fewer than 8 records.
pub fn sandwich(
    a: &DMatrix<f64>,
    e: &DVector<f64>,
    bread: &DMatrix<f64>,
    times: &[f64],
    rank: usize,
) -> Option<SerialCovariance> {
    let n = times.len();
    let p = a.ncols();
    if n < 8 || a.nrows() != 3 * n || e.len() != 3 * n || p == 0 {
        return None;
    }
    let blocks = BLOCKS.min(n);
    let fold = time_blocks(times, blocks);
    // block sums of the scores, projected by the bread: U_b = P Σ_{i∈b} Aᵢᵀeᵢ (p × blocks)
    let u = bread * score_sums(a, e, &fold, blocks);
    let lag_blocks = andrews_bartlett_lag(&u);
    let mut s = &u * u.transpose();
    for l in 1..=lag_blocks {
        let w = 1.0 - l as f64 / (lag_blocks as f64 + 1.0);
        let lead = u.columns(l, blocks - l);
        let lagged = u.columns(0, blocks - l);
        let c = lead * lagged.transpose();
        s += (&c + c.transpose()) * w;
    }
    let rows = 3 * n;
    let dof = rows.saturating_sub(rank).max(1);
    Some(SerialCovariance {
        covariance: s * (rows as f64 / dof as f64),
        blocks,
        lag_blocks,
    })
}

/// Cells per axis of the workspace grid the scores are clustered on by [`by_place`].
pub const PLACE_CELLS: usize = 16;

/// The sandwich with the scores clustered by place instead of time: records whose positions
/// fall in one cell of a [`PLACE_CELLS`]³ grid over the workspace form a cluster, clusters
/// independent (S = G/(G−1) Σ_c U_c U_cᵀ). A static error the model lacks (a sensor's offset
/// seen through a thermal term, sub-µm structure left unexplained) repeats at a place every
/// time the program returns there, so it correlates residuals across the whole recording, not
/// within a stretch of time: the clusters by place see it where blocks of time cannot. None with
/// fewer than 8 occupied cells.
pub fn by_place(
    a: &DMatrix<f64>,
    e: &DVector<f64>,
    bread: &DMatrix<f64>,
    positions: &[nalgebra::Vector3<f64>],
    rank: usize,
) -> Option<DMatrix<f64>> {
    let n = positions.len();
    let p = a.ncols();
    if n < 8 || a.nrows() != 3 * n || e.len() != 3 * n || p == 0 {
        return None;
    }
    let (lo, hi) = positions.iter().fold(
        (
            nalgebra::Vector3::repeat(f64::INFINITY),
            nalgebra::Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(l, h), q| (l.inf(q), h.sup(q)),
    );
    let size = (hi - lo).max() / PLACE_CELLS as f64;
    let key = |q: &nalgebra::Vector3<f64>| -> [i64; 3] {
        let c = |k: usize| {
            if size > 0.0 {
                (((q[k] - lo[k]) / size).floor() as i64).min(PLACE_CELLS as i64 - 1)
            } else {
                0
            }
        };
        [c(0), c(1), c(2)]
    };
    let mut cells: std::collections::BTreeMap<[i64; 3], usize> = std::collections::BTreeMap::new();
    let cluster: Vec<usize> = positions
        .iter()
        .map(|q| {
            let next = cells.len();
            *cells.entry(key(q)).or_insert(next)
        })
        .collect();
    let g_count = cells.len();
    if g_count < 8 {
        return None;
    }
    let u = bread * score_sums(a, e, &cluster, g_count);
    let rows = 3 * n;
    let dof = rows.saturating_sub(rank).max(1);
    Some(&u * u.transpose() * (g_count as f64 / (g_count - 1) as f64) * (rows as f64 / dof as f64))
}

/// How far the least-squares solution with columns `a` (residuals `e`, `bread` = (AᵀA)⁺) moves
/// when the columns `c` are added to the fit (block elimination: δ = (CᵀMC)⁺Cᵀe for the new
/// coefficients, −P·AᵀC·δ for the old ones, M = I − A·P·Aᵀ). None when `c` adds nothing.
pub fn shift_if_added(
    a: &DMatrix<f64>,
    e: &DVector<f64>,
    bread: &DMatrix<f64>,
    c: &DMatrix<f64>,
) -> Option<DVector<f64>> {
    if c.ncols() == 0 || c.nrows() != a.nrows() {
        return None;
    }
    let atc = a.tr_mul(c);
    let pc = bread * &atc;
    let schur = c.tr_mul(c) - atc.transpose() * &pc;
    let (inv, rank) = crate::blocked_least_squares::pseudo_inverse(&schur);
    if rank == 0 {
        return None;
    }
    let delta = inv * c.tr_mul(e);
    Some(-(pc * delta))
}

/// Σ over the records of each group of Aᵢᵀeᵢ (p × groups).
fn score_sums(a: &DMatrix<f64>, e: &DVector<f64>, group: &[usize], groups: usize) -> DMatrix<f64> {
    let p = a.ncols();
    let mut g = DMatrix::zeros(p, groups);
    for (i, &b) in group.iter().enumerate() {
        for r in 3 * i..3 * i + 3 {
            let er = e[r];
            if er != 0.0 {
                for j in 0..p {
                    g[(j, b)] += a[(r, j)] * er;
                }
            }
        }
    }
    g
}

/// Andrews (1991) automatic lag window for Bartlett weights, from AR(1) fits to each
/// (standardised) row of `u` (one series per parameter): ⌈1.1447 (α̂(1)·T)^{1/3}⌉, at most
/// T/4 — a window beyond that leaves too few blocks to estimate the covariance.
fn andrews_bartlett_lag(u: &DMatrix<f64>) -> usize {
    let t = u.ncols();
    let (mut num, mut den) = (0.0, 0.0);
    for j in 0..u.nrows() {
        let x = u.row(j);
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for k in 1..t {
            sxy += x[k] * x[k - 1];
            sxx += x[k - 1] * x[k - 1];
        }
        if !(sxx > 0.0) {
            continue;
        }
        let rho = (sxy / sxx).clamp(-0.97, 0.97);
        let var = (1..t).map(|k| (x[k] - rho * x[k - 1]).powi(2)).sum::<f64>() / (t - 1) as f64;
        if !(var > 0.0) {
            continue;
        }
        // standardised (innovation variance over the series' own): each parameter weighs the
        // same whatever its unit
        let m2 = x.iter().map(|v| v * v).sum::<f64>() / t as f64;
        let s4 = (var / m2).powi(2);
        num += 4.0 * rho * rho * s4 / ((1.0 - rho).powi(6) * (1.0 + rho).powi(2));
        den += s4 / (1.0 - rho).powi(4);
    }
    if !(den > 0.0) {
        return 1;
    }
    let alpha = num / den;
    let lag = (1.1447 * (alpha * t as f64).cbrt()).ceil() as usize;
    lag.clamp(1, (t / 4).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A mean and a trend fitted to (a) white noise, (b) AR(1) noise correlated over 10
    /// records (a block of time holds 10): the sandwich σ of the mean agrees with the independent-rows σ for (a) and with
    /// the spread over many seeds for (b), where the independent-rows σ is several times too
    /// small.
    #[test]
    fn sandwich_follows_the_correlation() {
        let n = 2000;
        let times: Vec<f64> = (0..n).map(|i| i as f64).collect();
        // three rows per record: the mean on row 0, nothing on rows 1, 2
        let mut a = DMatrix::zeros(3 * n, 2);
        for i in 0..n {
            a[(3 * i, 0)] = 1.0;
            a[(3 * i, 1)] = (i as f64 / n as f64) - 0.5;
        }
        let ata = a.tr_mul(&a);
        let bread = ata.clone().try_inverse().unwrap();
        let run = |phi: f64, seed: u64| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut e = DVector::zeros(3 * n);
            let mut z = 0.0f64;
            for i in 0..n {
                let w: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
                z = phi * z + (1.0 - phi * phi).sqrt() * w;
                e[3 * i] = z;
                e[3 * i + 1] = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
                e[3 * i + 2] = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
            }
            let x = &bread * a.tr_mul(&e);
            let res = &e - &a * &x;
            let sigma2 = res.norm_squared() / (3 * n - 2) as f64;
            let classical = (bread[(0, 0)] * sigma2).sqrt();
            let s = sandwich(&a, &res, &bread, &times, 2).unwrap();
            (x[0], classical, s.covariance[(0, 0)].sqrt(), s.lag_blocks)
        };
        let (_, c, h, lag) = run(0.0, 1);
        assert!(
            (h / c - 1.0).abs() < 0.2,
            "white: sandwich {h} vs classical {c} (lag {lag})"
        );
        let phi = (-1.0f64 / 10.0).exp();
        let runs: Vec<_> = (0..60).map(|s| run(phi, 100 + s)).collect();
        let spread = (runs.iter().map(|r| r.0 * r.0).sum::<f64>() / runs.len() as f64).sqrt();
        let hac = (runs.iter().map(|r| r.2 * r.2).sum::<f64>() / runs.len() as f64).sqrt();
        let classical = (runs.iter().map(|r| r.1 * r.1).sum::<f64>() / runs.len() as f64).sqrt();
        assert!(
            classical < 0.5 * spread,
            "AR(1): classical {classical} vs spread {spread}"
        );
        assert!(
            hac > 0.75 * spread && hac < 1.3 * spread,
            "AR(1): sandwich {hac} vs spread {spread}"
        );
    }
}
