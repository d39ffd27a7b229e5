//! The weighted normal equations A = J̃ᵀJ̃, g = J̃ᵀr̃ (J̃, r̃ whitened and robust-weighted) built
//! from the m × n Jacobian in place, and the small dense solves on them.
//!
//! The Jacobian is stored column-major and multiplied by itself a block of rows at a time (no Jᵀ
//! copy, no m × m weight matrix: a 10 000 × 70 problem touches only its 5.6 MB Jacobian, a
//! block buffer and a 70 × 70 matrix).

use crate::gram_kernel::weighted_gram_of_rows;
use nalgebra::{DMatrix, DVector};

/// The weighted normal equations on the free columns: with `row_scale` = √Wᵢ/σᵢ and `r` the
/// already weighted residuals, A = J̃ᵀJ̃ and g = J̃ᵀr̃ with J̃ = diag(row_scale)·J[:, free], into
/// the n × n `a` and the n-vector `g`, zero in the rows and columns of the parameters not in `free`.
///
/// Fused and blocked ([`crate::gram_kernel`]): a block of rows of J's free columns at a time is
/// weighted into a buffer that stays in cache and multiplied from there, so J is read from
/// memory once (scaling J in place, then multiplying it, read it three times), and the columns
/// of fixed parameters (a third of the XFYZ model's 75) are neither weighted nor multiplied. A
/// tall J is summed over its two halves of rows on two threads; the halves and the blocks are
/// fixed, so the rounding, and so the result, does not depend on the thread count.
pub(crate) fn accumulate_free(
    j: &DMatrix<f64>,
    free: &[usize],
    row_scale: &[f64],
    r: Option<&[f64]>,
    a: &mut DMatrix<f64>,
    g: &mut DVector<f64>,
) {
    let (m, n) = j.shape();
    assert!(
        row_scale.len() == m
            && r.is_none_or(|r| r.len() == m)
            && a.shape() == (n, n)
            && g.len() == n,
        "accumulate_free: shapes disagree"
    );
    let (af, gf) = free_gram(j, free, row_scale, r);
    scatter_free(&af, free, a);
    g.fill(0.0);
    for (c, &k) in free.iter().enumerate() {
        g[k] = gf[c];
    }
}

/// J̃ᵀJ̃ (|free| × |free|, exactly symmetric: the kernel forms one triangle and mirrors it) and
/// J̃ᵀr̃ (zero without r) of [`accumulate_free`], in the free columns' order.
fn free_gram(
    j: &DMatrix<f64>,
    free: &[usize],
    row_scale: &[f64],
    r: Option<&[f64]>,
) -> (DMatrix<f64>, DVector<f64>) {
    let m = j.nrows();
    let nf = free.len();
    let (mut af, mut gf) = (DMatrix::zeros(nf, nf), DVector::zeros(nf));
    if m < SPLIT_ROWS {
        weighted_gram_of_rows(j, free, row_scale, r, 0..m, &mut af, &mut gf);
    } else {
        let half = m / 2;
        let (mut af2, mut gf2) = (DMatrix::zeros(nf, nf), DVector::zeros(nf));
        std::thread::scope(|scope| {
            let worker = scope.spawn(|| {
                weighted_gram_of_rows(j, free, row_scale, r, half..m, &mut af2, &mut gf2)
            });
            weighted_gram_of_rows(j, free, row_scale, r, 0..half, &mut af, &mut gf);
            worker
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
        });
        af += af2;
        gf += gf2;
    }
    (af, gf)
}

/// The n × n `a` with the |free| × |free| `known` in the rows and columns `free`, zero elsewhere.
pub(crate) fn scatter_free(known: &DMatrix<f64>, free: &[usize], a: &mut DMatrix<f64>) {
    a.fill(0.0);
    for (c, &k) in free.iter().enumerate() {
        for (d, &l) in free.iter().enumerate() {
            a[(k, l)] = known[(c, d)];
        }
    }
}

/// g = Jᵀr on the columns `free` (unit weights), zero elsewhere: the gradient alone, for when
/// the normal matrix is already known ([`scatter_free`]).
pub(crate) fn gradient_free(j: &DMatrix<f64>, free: &[usize], r: &[f64], g: &mut DVector<f64>) {
    g.fill(0.0);
    for &k in free {
        g[k] = j.column(k).iter().zip(r).map(|(v, ri)| v * ri).sum();
    }
}

/// JᵀJ of the columns `columns` of `j` (|columns| × |columns|), formed as the solver forms its
/// normal matrix (see [`accumulate_free`]), for an identifiability analysis of a Jacobian the
/// caller holds ([`crate::Identifiability::from_normal_matrix`]).
pub fn normal_matrix(j: &DMatrix<f64>, columns: &[usize]) -> DMatrix<f64> {
    free_gram(j, columns, &vec![1.0; j.nrows()], None).0
}

/// The first non-finite entry (row, column) of `j` in the columns `free`, or None.
///
/// Each column is scanned in lanes of 8 summing v·0, which stays 0 for finite v and becomes NaN
/// for ±∞ or NaN; the lanes are independent, so the loop vectorises (a `position` search with
/// an early exit does not, and scanned the 30 000 × 75 Jacobian of the XFYZ fit at a twentieth
/// of memory speed). Only a column that fails is searched entry by entry to name the entry.
pub(crate) fn first_non_finite(j: &DMatrix<f64>, free: &[usize]) -> Option<(usize, usize)> {
    for &k in free {
        let col = j.column(k);
        let col = col.as_slice();
        let mut lanes = [0.0f64; 8];
        let chunks = col.chunks_exact(8);
        let tail = chunks.remainder();
        for chunk in chunks {
            for (l, v) in lanes.iter_mut().zip(chunk) {
                *l += v * 0.0;
            }
        }
        let finite = lanes.iter().all(|l| *l == 0.0) && tail.iter().all(|v| v.is_finite());
        if !finite {
            return col.iter().position(|v| !v.is_finite()).map(|i| (i, k));
        }
    }
    None
}

/// Rows from which [`accumulate_free`] splits the product over two threads (below, a thread
/// costs more than it saves).
const SPLIT_ROWS: usize = 4096;

/// Solves M x = b for symmetric positive definite M by Cholesky, overwriting M's lower triangle
/// with the factor and b with x. False if M is not (numerically) positive definite.
pub(crate) fn cholesky_solve_in_place(m: &mut DMatrix<f64>, b: &mut [f64]) -> bool {
    let n = m.nrows();
    for k in 0..n {
        let mut d = m[(k, k)];
        for p in 0..k {
            d -= m[(k, p)] * m[(k, p)];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let l = d.sqrt();
        m[(k, k)] = l;
        for i in k + 1..n {
            let mut v = m[(i, k)];
            for p in 0..k {
                v -= m[(i, p)] * m[(k, p)];
            }
            m[(i, k)] = v / l;
        }
    }
    for i in 0..n {
        let mut v = b[i];
        for p in 0..i {
            v -= m[(i, p)] * b[p];
        }
        b[i] = v / m[(i, i)];
    }
    for i in (0..n).rev() {
        let mut v = b[i];
        for p in i + 1..n {
            v -= m[(p, i)] * b[p];
        }
        b[i] = v / m[(i, i)];
    }
    true
}

/// (D⁻¹AD⁻¹) restricted to `free`, with D = √diag(A) (unit diagonal; zero diagonals scale by 1),
/// as (matrix, indices of the free parameters, D of each).
pub(crate) fn scaled_free_block(
    a: &DMatrix<f64>,
    free: &[bool],
) -> (DMatrix<f64>, Vec<usize>, Vec<f64>) {
    let idx: Vec<usize> = (0..a.nrows()).filter(|&k| free[k]).collect();
    let d: Vec<f64> = idx
        .iter()
        .map(|&k| {
            if a[(k, k)] > 0.0 {
                a[(k, k)].sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let s = DMatrix::from_fn(idx.len(), idx.len(), |i, j| {
        a[(idx[i], idx[j])] / (d[i] * d[j])
    });
    (s, idx, d)
}

/// A⁻¹ on the free parameters (zero rows/columns elsewhere), or None when A restricted to them is
/// singular: the smallest eigenvalue of the unit-diagonal scaled matrix below 1e-12 of the largest
/// (a condition number above 10⁶ in the column-scaled Jacobian's singular values).
pub(crate) fn free_inverse(a: &DMatrix<f64>, free: &[bool]) -> Option<DMatrix<f64>> {
    let n = a.nrows();
    let (s, idx, d) = scaled_free_block(a, free);
    let mut out = DMatrix::zeros(n, n);
    if idx.is_empty() {
        return Some(out);
    }
    let eig = s.symmetric_eigen();
    let max = eig.eigenvalues.max();
    if !(max > 0.0) || eig.eigenvalues.iter().any(|&l| !(l > 1e-12 * max)) {
        return None;
    }
    let v = &eig.eigenvectors;
    for (i, &ki) in idx.iter().enumerate() {
        for (j, &kj) in idx.iter().enumerate() {
            let mut acc = 0.0;
            for e in 0..idx.len() {
                acc += v[(i, e)] * v[(j, e)] / eig.eigenvalues[e];
            }
            out[(ki, kj)] = acc / (d[i] * d[j]);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_equations_and_cholesky_match_nalgebra() {
        let j = DMatrix::from_fn(37, 5, |i, k| {
            ((i * 7 + k * 3) % 11) as f64 - 5.0 + 0.1 * k as f64
        });
        let r: Vec<f64> = (0..37).map(|i| (i as f64).sin()).collect();
        let (mut a, mut g) = (DMatrix::zeros(5, 5), DVector::zeros(5));
        accumulate_free(&j, &[0, 1, 2, 3, 4], &[1.0; 37], Some(&r), &mut a, &mut g);
        let a_ref = j.transpose() * &j;
        let g_ref = j.transpose() * DVector::from_column_slice(&r);
        assert!((&a - &a_ref).amax() < 1e-12 * a_ref.amax());
        assert!((&g - &g_ref).amax() < 1e-12 * g_ref.amax());
        let mut m = a.clone();
        let mut b = g.as_slice().to_vec();
        assert!(cholesky_solve_in_place(&mut m, &mut b));
        let x_ref = a_ref.clone().cholesky().unwrap().solve(&g_ref);
        for k in 0..5 {
            assert!((b[k] - x_ref[k]).abs() < 1e-10 * x_ref.amax(), "x[{k}]");
        }
        let inv = free_inverse(&a, &[true; 5]).unwrap();
        assert!((inv * &a_ref - DMatrix::identity(5, 5)).amax() < 1e-9);
        let mut singular = a.clone();
        singular.column_mut(4).fill(0.0);
        singular.row_mut(4).fill(0.0);
        assert!(free_inverse(&singular, &[true; 5]).is_none());
        assert!(free_inverse(&singular, &[true, true, true, true, false]).is_some());
    }
}
