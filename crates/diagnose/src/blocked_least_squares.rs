//! Least squares on whitened rows grouped in blocks, fast enough to score hundreds of candidate
//! columns against hundreds of thousands of rows.
//!
//! Every row belongs to one fold of each blocking scheme (blocks of time, blocks of workspace);
//! rows sharing all their folds form a *cell*. Rows are stored cell by cell, so the normal
//! equations of any column set can be summed per cell with contiguous matrix products; the
//! training sums of a fold are the total minus that fold's cells. A candidate's extra columns
//! enter by block elimination (Schur complement) against the pseudo-inverse of the base columns,
//! so its cost is O(rows · columns) once, then small dense algebra per fold.
//!
//! Solves use the column-scaled normal matrix and its symmetric eigen-decomposition; directions
//! with eigenvalue below [`RANK_TOLERANCE`] of the largest are treated as not identifiable
//! (minimum-norm solution), which is also how a candidate that the base columns already explain
//! is recognised (its Schur complement is singular).

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

/// Relative eigenvalue of the scaled normal matrix below which a direction is not identifiable
/// (1e-11 on eigenvalues = about 3e-6 on singular values).
pub const RANK_TOLERANCE: f64 = 1e-11;

/// Share of a candidate column's squared norm (in the candidate's own column scaling) that must
/// be left after projecting out the base columns for it to count as separable from them: a
/// column the base already spans keeps almost nothing (1e-8 = 1e-4 of its norm).
pub const SEPARABLE_TOLERANCE: f64 = 1e-8;

/// Rows arranged cell by cell, with the fold of each cell in each scheme.
#[derive(Debug, Clone)]
pub struct BlockedRows {
    /// Arranged row k is original row `order[k]`.
    order: Vec<usize>,
    /// Arranged rows of each cell.
    cells: Vec<Range<usize>>,
    /// fold_of_cell[scheme][cell].
    fold_of_cell: Vec<Vec<usize>>,
    /// Number of folds of each scheme.
    fold_counts: Vec<usize>,
}

impl BlockedRows {
    /// `row_folds[scheme][row]` = fold of that row in that scheme (0..k).
    pub fn new(row_folds: &[Vec<usize>], rows: usize) -> Self {
        let key = |r: usize| row_folds.iter().map(|f| f[r]).collect::<Vec<_>>();
        let mut order: Vec<usize> = (0..rows).collect();
        order.sort_by_key(|&r| key(r));
        let mut cells = Vec::new();
        let mut fold_of_cell: Vec<Vec<usize>> = vec![Vec::new(); row_folds.len()];
        let mut start = 0;
        while start < rows {
            let k = key(order[start]);
            let mut end = start + 1;
            while end < rows && key(order[end]) == k {
                end += 1;
            }
            cells.push(start..end);
            for (s, f) in k.iter().enumerate() {
                fold_of_cell[s].push(*f);
            }
            start = end;
        }
        let fold_counts = row_folds
            .iter()
            .map(|f| f.iter().copied().max().map(|m| m + 1).unwrap_or(0))
            .collect();
        Self {
            order,
            cells,
            fold_of_cell,
            fold_counts,
        }
    }

    pub fn rows(&self) -> usize {
        self.order.len()
    }

    /// The rows of `m` in arranged order.
    pub fn arrange(&self, m: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(self.order.len(), m.ncols(), |k, j| m[(self.order[k], j)])
    }

    pub fn arrange_vector(&self, v: &DVector<f64>) -> DVector<f64> {
        DVector::from_fn(self.order.len(), |k, _| v[self.order[k]])
    }

    /// Back to the original row order.
    pub fn restore_vector(&self, v: &DVector<f64>) -> DVector<f64> {
        let mut out = DVector::zeros(v.len());
        for (k, &r) in self.order.iter().enumerate() {
            out[r] = v[k];
        }
        out
    }

    /// Every (scheme, fold) with the cells it holds out.
    fn folds(&self) -> Vec<(usize, Vec<usize>)> {
        let mut out = Vec::new();
        for (s, &k) in self.fold_counts.iter().enumerate() {
            for f in 0..k {
                let cells: Vec<usize> = (0..self.cells.len())
                    .filter(|&c| self.fold_of_cell[s][c] == f)
                    .collect();
                if !cells.is_empty() {
                    out.push((s, cells));
                }
            }
        }
        out
    }

    pub fn scheme_count(&self) -> usize {
        self.fold_counts.len()
    }
}

/// Which eigenvalues of a scaled symmetric matrix count as directions.
#[derive(Clone, Copy)]
enum Keep {
    /// Above this fraction of the largest.
    Relative(f64),
    /// Above this value.
    Absolute(f64),
}

/// Pseudo-inverse of the symmetric matrix `m`, scaled by the diagonal of `scale` (columns to
/// unit norm) before its eigen-decomposition, and its rank.
fn scaled_pseudo_inverse(
    m: &DMatrix<f64>,
    scale: &DMatrix<f64>,
    keep: Keep,
) -> (DMatrix<f64>, usize) {
    let p = m.nrows();
    if p == 0 {
        return (DMatrix::zeros(0, 0), 0);
    }
    let d: Vec<f64> = (0..p)
        .map(|i| {
            if scale[(i, i)] > 0.0 {
                1.0 / scale[(i, i)].sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let scaled = DMatrix::from_fn(p, p, |i, j| m[(i, j)] * d[i] * d[j]);
    let eig = scaled.symmetric_eigen();
    let floor = match keep {
        Keep::Relative(f) => f * eig.eigenvalues.iter().cloned().fold(0.0, f64::max),
        Keep::Absolute(a) => a,
    };
    let mut inv = DMatrix::zeros(p, p);
    let mut rank = 0;
    for (k, &l) in eig.eigenvalues.iter().enumerate() {
        if l > floor && l > 0.0 {
            rank += 1;
            let v = eig.eigenvectors.column(k);
            inv += v * v.transpose() / l;
        }
    }
    for i in 0..p {
        for j in 0..p {
            inv[(i, j)] *= d[i] * d[j];
        }
    }
    (inv, rank)
}

/// Pseudo-inverse of a symmetric positive semi-definite matrix by column scaling and eigen-
/// decomposition (directions below [`RANK_TOLERANCE`] of the largest dropped), and its rank.
pub fn pseudo_inverse(g: &DMatrix<f64>) -> (DMatrix<f64>, usize) {
    scaled_pseudo_inverse(g, g, Keep::Relative(RANK_TOLERANCE))
}

/// Normal-equation sums of columns `a` (arranged) per cell.
#[derive(Debug, Clone)]
struct CellSums {
    g: Vec<DMatrix<f64>>,
    h: Vec<DVector<f64>>,
    s: Vec<f64>,
}

fn cell_sums(rows: &BlockedRows, a: &DMatrix<f64>, b: &DVector<f64>) -> CellSums {
    let mut out = CellSums {
        g: Vec::new(),
        h: Vec::new(),
        s: Vec::new(),
    };
    for r in &rows.cells {
        let ac = a.rows(r.start, r.len());
        let bc = b.rows(r.start, r.len());
        out.g.push(ac.tr_mul(&ac));
        out.h.push(ac.tr_mul(&bc));
        out.s.push(bc.norm_squared());
    }
    out
}

/// The fitted base columns (declared, then the terms chosen so far), ready to score candidates.
#[derive(Debug, Clone)]
pub struct BaseFit {
    b: DVector<f64>,
    a: DMatrix<f64>,
    /// Full data: pseudo-inverse, h, solution, SSR, rank.
    full: Solved,
    /// Per held-out fold: (scheme, cells, training solve, test sums).
    folds: Vec<FoldFit>,
}

#[derive(Debug, Clone)]
struct Solved {
    p: DMatrix<f64>,
    h: DVector<f64>,
    x: DVector<f64>,
    ssr: f64,
    rank: usize,
}

#[derive(Debug, Clone)]
struct FoldFit {
    scheme: usize,
    cells: Vec<usize>,
    train: Solved,
    test_g: DMatrix<f64>,
    test_h: DVector<f64>,
    test_s: f64,
}

fn solve(g: &DMatrix<f64>, h: &DVector<f64>, s: f64) -> Solved {
    let (p, rank) = pseudo_inverse(g);
    let x = &p * h;
    let ssr = (s - h.dot(&x)).max(0.0);
    Solved {
        p,
        h: h.clone(),
        x,
        ssr,
        rank,
    }
}

/// How one candidate column block does against a base fit.
#[derive(Debug, Clone)]
pub struct CandidateFit {
    /// Its coefficients on the full data.
    pub values: DVector<f64>,
    /// (S⁻¹): their covariance up to the variance factor.
    pub unscaled_covariance: DMatrix<f64>,
    /// SSR of the full-data fit with the candidate.
    pub ssr: f64,
    /// Rank of base + candidate.
    pub rank: usize,
    /// The candidate adds as many independent directions as it has columns.
    pub separable: bool,
    /// Held-out SSR summed over every fold of every scheme.
    pub heldout_ssr: f64,
    /// Held-out SSR of each scheme.
    pub heldout_by_scheme: Vec<f64>,
    /// SSR reduction the candidate explains, rhsᵀS⁻¹rhs.
    pub explained: f64,
}

impl BaseFit {
    /// Fit the base columns `a` (arranged rows) to `b` (arranged).
    pub fn new(rows: &BlockedRows, a: DMatrix<f64>, b: DVector<f64>) -> Self {
        let sums = cell_sums(rows, &a, &b);
        let p = a.ncols();
        let total_g = sums.g.iter().fold(DMatrix::zeros(p, p), |acc, g| acc + g);
        let total_h = sums.h.iter().fold(DVector::zeros(p), |acc, h| acc + h);
        let total_s: f64 = sums.s.iter().sum();
        let full = solve(&total_g, &total_h, total_s);
        let mut folds = Vec::new();
        for (scheme, cells) in rows.folds() {
            let test_g = cells
                .iter()
                .fold(DMatrix::zeros(p, p), |acc, &c| acc + &sums.g[c]);
            let test_h = cells
                .iter()
                .fold(DVector::zeros(p), |acc, &c| acc + &sums.h[c]);
            let test_s: f64 = cells.iter().map(|&c| sums.s[c]).sum();
            let train = solve(
                &(&total_g - &test_g),
                &(&total_h - &test_h),
                total_s - test_s,
            );
            folds.push(FoldFit {
                scheme,
                cells,
                train,
                test_g,
                test_h,
                test_s,
            });
        }
        Self { b, a, full, folds }
    }

    pub fn ssr(&self) -> f64 {
        self.full.ssr
    }
    pub fn rank(&self) -> usize {
        self.full.rank
    }
    pub fn rows(&self) -> usize {
        self.b.len()
    }
    /// The base columns' full-data solution.
    pub fn solution(&self) -> &DVector<f64> {
        &self.full.x
    }
    /// The base columns' full-data pseudo-inverse (JᵀJ)⁺.
    pub fn unscaled_covariance(&self) -> &DMatrix<f64> {
        &self.full.p
    }
    pub fn columns(&self) -> &DMatrix<f64> {
        &self.a
    }

    /// Held-out SSR of the base columns, summed over every fold of every scheme.
    pub fn heldout_ssr(&self) -> f64 {
        self.heldout_by_scheme().iter().sum()
    }

    /// Held-out SSR of the base columns, per scheme.
    pub fn heldout_by_scheme(&self) -> Vec<f64> {
        let schemes = self.folds.iter().map(|f| f.scheme + 1).max().unwrap_or(0);
        let mut out = vec![0.0; schemes];
        for f in &self.folds {
            out[f.scheme] += f.test_s - 2.0 * f.train.x.dot(&f.test_h)
                + f.train.x.dot(&(&f.test_g * &f.train.x));
        }
        out
    }

    /// Held-out residual of every (arranged) row, one vector per scheme.
    pub fn heldout_residuals(&self, rows: &BlockedRows) -> Vec<DVector<f64>> {
        let mut out = vec![DVector::zeros(self.b.len()); rows.scheme_count()];
        for f in &self.folds {
            for &c in &f.cells {
                let r = &rows.cells[c];
                let pred = self.a.rows(r.start, r.len()) * &f.train.x;
                out[f.scheme]
                    .rows_mut(r.start, r.len())
                    .copy_from(&(self.b.rows(r.start, r.len()) - pred));
            }
        }
        out
    }

    /// `v` (arranged rows) with its least-squares fit by the base columns taken out: what of it
    /// the base cannot explain.
    pub fn project_out(&self, v: &DVector<f64>) -> DVector<f64> {
        v - &self.a * (&self.full.p * self.a.tr_mul(v))
    }

    /// Full-data residual of every (arranged) row.
    pub fn residuals(&self) -> DVector<f64> {
        &self.b - &self.a * &self.full.x
    }

    /// Score extra columns `c` (arranged rows) added to the base.
    pub fn candidate(&self, rows: &BlockedRows, c: &DMatrix<f64>) -> CandidateFit {
        let k = c.ncols();
        let p = self.a.ncols();
        let mut cross = Vec::with_capacity(rows.cells.len());
        let mut cc = Vec::with_capacity(rows.cells.len());
        let mut cb = Vec::with_capacity(rows.cells.len());
        for r in &rows.cells {
            let ac = self.a.rows(r.start, r.len());
            let candc = c.rows(r.start, r.len());
            cross.push(ac.tr_mul(&candc));
            cc.push(candc.tr_mul(&candc));
            cb.push(candc.tr_mul(&self.b.rows(r.start, r.len())));
        }
        let sum_m =
            |v: &[DMatrix<f64>], cells: &mut dyn Iterator<Item = usize>, r: usize, c: usize| {
                cells.fold(DMatrix::zeros(r, c), |acc, i| acc + &v[i])
            };
        let all = || 0..rows.cells.len();
        let x_all = sum_m(&cross, &mut all(), p, k);
        let cc_all = sum_m(&cc, &mut all(), k, k);
        let cb_all = cb.iter().fold(DVector::zeros(k), |acc, v| acc + v);
        // full data: Schur complement of the base block
        let (y, s_inv, explained, sep_rank) = schur(&self.full, &x_all, &cc_all, &cb_all);
        let ssr = (self.full.ssr - explained).max(0.0);
        let schemes = self.folds.iter().map(|f| f.scheme + 1).max().unwrap_or(0);
        let mut by_scheme = vec![0.0; schemes];
        for f in &self.folds {
            let xt = sum_m(&cross, &mut f.cells.iter().copied(), p, k);
            let cct = sum_m(&cc, &mut f.cells.iter().copied(), k, k);
            let cbt = f
                .cells
                .iter()
                .fold(DVector::zeros(k), |acc, &i| acc + &cb[i]);
            let (yf, _, _, _) = schur(
                &f.train,
                &(&x_all - &xt),
                &(&cc_all - &cct),
                &(&cb_all - &cbt),
            );
            // base coefficients of the training fit with the candidate: x = P(h − X y)
            let xf = &f.train.p * (&f.train.h - (&x_all - &xt) * &yf);
            let quad =
                xf.dot(&(&f.test_g * &xf)) + 2.0 * xf.dot(&(&xt * &yf)) + yf.dot(&(&cct * &yf));
            by_scheme[f.scheme] += f.test_s - 2.0 * (xf.dot(&f.test_h) + yf.dot(&cbt)) + quad;
        }
        CandidateFit {
            values: y,
            unscaled_covariance: s_inv,
            ssr,
            rank: self.full.rank + sep_rank,
            separable: sep_rank == k,
            heldout_ssr: by_scheme.iter().sum(),
            heldout_by_scheme: by_scheme,
            explained,
        }
    }
}

/// Block elimination of extra columns against a solved base: S = CᵀC − XᵀPX, rhs = Cᵀb − XᵀPh;
/// returns (S⁺·rhs, S⁺, rhsᵀS⁺rhs, rank of S).
fn schur(
    base: &Solved,
    x: &DMatrix<f64>,
    cc: &DMatrix<f64>,
    cb: &DVector<f64>,
) -> (DVector<f64>, DMatrix<f64>, f64, usize) {
    let px = &base.p * x;
    let s = cc - x.tr_mul(&px);
    let s = (&s + s.transpose()) * 0.5;
    let rhs = cb - px.tr_mul(&base.h);
    // rank relative to the candidate's own scale: a column the base already spans keeps almost
    // nothing of its norm after elimination
    let (inv, rank) = scaled_inverse(&s, cc);
    let y = &inv * &rhs;
    let explained = rhs.dot(&y);
    (y, inv, explained, rank)
}

/// Pseudo-inverse of a Schur complement `s` in the scaling of the candidate's own columns
/// (`cc` = their normal matrix), directions below [`SEPARABLE_TOLERANCE`] dropped; and its rank.
fn scaled_inverse(s: &DMatrix<f64>, cc: &DMatrix<f64>) -> (DMatrix<f64>, usize) {
    scaled_pseudo_inverse(s, cc, Keep::Absolute(SEPARABLE_TOLERANCE))
}

/// The columns of `c` (whitened, any row order) that, taken in order, each add a direction the
/// base columns `a` (with `a_pinv` = (aᵀa)⁺) and the columns kept before them do not span — by
/// the same test the selection applies, so what is kept is separable there.
pub fn separable_columns(a_pinv: &DMatrix<f64>, a: &DMatrix<f64>, c: &DMatrix<f64>) -> Vec<usize> {
    let mut kept: Vec<usize> = Vec::new();
    for j in 0..c.ncols() {
        if !(c.column(j).norm_squared() > 0.0) {
            continue;
        }
        let mut trial = kept.clone();
        trial.push(j);
        let sub = c.select_columns(&trial);
        let x = a.tr_mul(&sub);
        let s = sub.tr_mul(&sub) - x.tr_mul(&(a_pinv * &x));
        let (_, rank) = scaled_inverse(&((&s + s.transpose()) * 0.5), &sub.tr_mul(&sub));
        if rank == trial.len() {
            kept = trial;
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocked sums give what a direct solve on the selected rows gives.
    #[test]
    fn held_out_and_candidate_fits_match_direct_least_squares() {
        let n = 60;
        let a = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { i as f64 / n as f64 });
        let c = DMatrix::from_fn(n, 1, |i, _| ((i * 7) % 11) as f64 / 11.0);
        let b = DVector::from_fn(n, |i, _| {
            0.3 + 0.5 * i as f64 / n as f64 + 0.2 * c[(i, 0)] + ((i * 13) % 5) as f64 * 0.01
        });
        let time_folds: Vec<usize> = (0..n).map(|i| i * 3 / n).collect();
        let other: Vec<usize> = (0..n).map(|i| i % 2).collect();
        let rows = BlockedRows::new(&[time_folds.clone(), other.clone()], n);
        let base = BaseFit::new(&rows, rows.arrange(&a), rows.arrange_vector(&b));
        let cand = base.candidate(&rows, &rows.arrange(&c));
        // direct: full design [a c]
        let full = DMatrix::from_fn(n, 3, |i, j| if j < 2 { a[(i, j)] } else { c[(i, 0)] });
        let direct = full.clone().svd(true, true).solve(&b, 1e-14).unwrap();
        assert!(
            (cand.values[0] - direct[2]).abs() < 1e-9,
            "{} vs {}",
            cand.values[0],
            direct[2]
        );
        let ssr = (&b - &full * &direct).norm_squared();
        assert!((cand.ssr - ssr).abs() < 1e-9 * (1.0 + ssr));
        // held out, by hand
        let mut heldout = 0.0;
        for folds in [&time_folds, &other] {
            for f in 0..3 {
                let train: Vec<usize> = (0..n).filter(|&i| folds[i] != f).collect();
                let test: Vec<usize> = (0..n).filter(|&i| folds[i] == f).collect();
                if test.is_empty() {
                    continue;
                }
                let x = full
                    .select_rows(&train)
                    .svd(true, true)
                    .solve(&b.select_rows(&train), 1e-14)
                    .unwrap();
                heldout += (b.select_rows(&test) - full.select_rows(&test) * x).norm_squared();
            }
        }
        assert!(
            (cand.heldout_ssr - heldout).abs() < 1e-9 * (1.0 + heldout),
            "{} vs {heldout}",
            cand.heldout_ssr
        );
        assert!(cand.separable && cand.rank == 3);
        // a column the base already spans is recognised
        let spanned = DMatrix::from_fn(n, 1, |i, _| 2.0 - a[(i, 1)]);
        assert!(!base.candidate(&rows, &rows.arrange(&spanned)).separable);
    }
}
