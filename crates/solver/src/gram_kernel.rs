//! The weighted Gram matrix J̃ᵀJ̃ of a tall Jacobian's free columns, and J̃ᵀr̃, one block of rows
//! at a time: the product the solver forms at every accepted point.
//!
//! A general product (`matrixmultiply`'s dgemm) computes both triangles of the symmetric result
//! and packs its two operands on every call; here each block of rows is copied once, weighted,
//! into a row-major buffer that stays in L1, and only the tiles on and above the diagonal are
//! formed, each as TI × TJ accumulators held in registers across the block's rows (an outer
//! product per row: TI broadcasts, one TJ-wide load, TI·TJ multiply-adds). At the XFYZ fit's
//! 46 free columns that is 64 % of the full product's multiply-adds (with J̃ᵀr̃ riding along as
//! one more column). On 30 000 × 46, one core (`solver_benchmark`, its last line): 2.6–2.8 ms,
//! against 4.6–4.7 ms for nalgebra's Jᵀ·J (`matrixmultiply`'s dgemm) on the same columns
//! copied out beforehand, 1.7–1.8×. About half of the kernel's time is reading J from memory
//! into the blocks, which no kernel avoids.
//!
//! The default x86-64 target stops at SSE2; the same loops compiled for AVX2 with fused
//! multiply-adds run four lanes wide, chosen at run time so that the binary stays portable. The
//! two paths round differently (fused or not), so a result is reproducible on a machine, not
//! across machines with and without FMA. Each entry is summed in a fixed order (rows in
//! order within a block, blocks in order), independent of the thread count.

use nalgebra::{DMatrix, DVector};
use std::ops::Range;

/// Rows per block: 64 rows of 48 (padded) columns are 24 KB, within L1 with the accumulators.
const BLOCK_ROWS: usize = 64;
/// Register tile: TI columns of the block broadcast against TJ consecutive ones.
const TI: usize = 4;
const TJ: usize = 8;
const _: () = assert!(
    TJ.is_multiple_of(TI),
    "a row padded to whole TJ tiles holds whole TI tiles"
);

/// `af` = J̃ᵀJ̃ (|free| × |free|, both triangles) and `gf` = J̃ᵀr̃ (zero without r̃) over `rows`,
/// with J̃ = diag(row_scale)·J[:, free] and `r` already weighted.
pub(crate) fn weighted_gram_of_rows(
    j: &DMatrix<f64>,
    free: &[usize],
    row_scale: &[f64],
    r: Option<&[f64]>,
    rows: Range<usize>,
    af: &mut DMatrix<f64>,
    gf: &mut DVector<f64>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA (checked just above)
        unsafe { gram_avx2_fma(j, free, row_scale, r, rows, af, gf) };
        return;
    }
    gram(j, free, row_scale, r, rows, af, gf, tile_portable);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gram_avx2_fma(
    j: &DMatrix<f64>,
    free: &[usize],
    row_scale: &[f64],
    r: Option<&[f64]>,
    rows: Range<usize>,
    af: &mut DMatrix<f64>,
    gf: &mut DVector<f64>,
) {
    gram(
        j,
        free,
        row_scale,
        r,
        rows,
        af,
        gf,
        |block, w, kb, c0, d0, acc| {
            // SAFETY: this function runs only where AVX2 and FMA are (checked by the caller), and
            // `gram` hands over whole tiles within the block's rows
            unsafe { tile_avx2_fma(block, w, kb, c0, d0, acc) }
        },
    );
}

/// One TI × TJ tile over the block's kb rows, added into `acc`: the register kernel, two
/// 4-lane accumulators per broadcast column.
///
/// # Safety
/// AVX2 and FMA must be available; `block` must hold kb rows of w, and c0 + TI and d0 + TJ
/// must not exceed w.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn tile_avx2_fma(block: &[f64], w: usize, kb: usize, c0: usize, d0: usize, acc: &mut [f64]) {
    use std::arch::x86_64::*;
    assert!(
        kb * w <= block.len() && c0 + TI <= w && d0 + TJ <= w,
        "a tile within the block"
    );
    let mut t = [_mm256_setzero_pd(); 2 * TI];
    let p = block.as_ptr();
    for i in 0..kb {
        // SAFETY: row i's entries c0..c0 + TI and d0..d0 + TJ lie within the block (asserted)
        unsafe {
            let row = p.add(i * w);
            let (b0, b1) = (
                _mm256_loadu_pd(row.add(d0)),
                _mm256_loadu_pd(row.add(d0 + 4)),
            );
            for ii in 0..TI {
                let a = _mm256_broadcast_sd(&*row.add(c0 + ii));
                t[2 * ii] = _mm256_fmadd_pd(a, b0, t[2 * ii]);
                t[2 * ii + 1] = _mm256_fmadd_pd(a, b1, t[2 * ii + 1]);
            }
        }
    }
    for ii in 0..TI {
        let mut lanes = [0.0; TJ];
        // SAFETY: `lanes` holds TJ = 8 entries, two stores of 4
        unsafe {
            _mm256_storeu_pd(lanes.as_mut_ptr(), t[2 * ii]);
            _mm256_storeu_pd(lanes.as_mut_ptr().add(4), t[2 * ii + 1]);
        }
        for (jj, v) in lanes.iter().enumerate() {
            acc[(c0 + ii) * w + d0 + jj] += v;
        }
    }
}

/// [`tile_avx2_fma`] in portable code (separate multiply and add).
fn tile_portable(block: &[f64], w: usize, kb: usize, c0: usize, d0: usize, acc: &mut [f64]) {
    let mut t = [[0.0f64; TJ]; TI];
    for row in block[..kb * w].chunks_exact(w) {
        for ii in 0..TI {
            for jj in 0..TJ {
                t[ii][jj] += row[c0 + ii] * row[d0 + jj];
            }
        }
    }
    for (ii, ti) in t.iter().enumerate() {
        for (jj, v) in ti.iter().enumerate() {
            acc[(c0 + ii) * w + d0 + jj] += v;
        }
    }
}

/// The blocked product, with `tile(block, w, kb, c0, d0, acc)` adding one tile's sums.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn gram(
    j: &DMatrix<f64>,
    free: &[usize],
    row_scale: &[f64],
    r: Option<&[f64]>,
    rows: Range<usize>,
    af: &mut DMatrix<f64>,
    gf: &mut DVector<f64>,
    mut tile: impl FnMut(&[f64], usize, usize, usize, usize, &mut [f64]),
) {
    let nf = free.len();
    af.fill(0.0);
    gf.fill(0.0);
    if nf == 0 || rows.is_empty() {
        return;
    }
    // row-major, block[i·w + c] = J̃[b0 + i, c]; column nf holds r̃ (so the tiles' products
    // with it are J̃ᵀr̃), the rest up to a whole number of TJ tiles is zero padding
    let w = (nf + 1).next_multiple_of(TJ);
    let mut block = vec![0.0; BLOCK_ROWS * w];
    // the tiles on and above the diagonal, row-major w × w
    let mut acc = vec![0.0; w * w];
    let m = j.nrows();
    let mut b0 = rows.start;
    while b0 < rows.end {
        let kb = BLOCK_ROWS.min(rows.end - b0);
        let scale = &row_scale[b0..b0 + kb];
        for (c, &k) in free.iter().enumerate() {
            let src = &j.as_slice()[k * m + b0..k * m + b0 + kb];
            for (i, (v, s)) in src.iter().zip(scale).enumerate() {
                block[i * w + c] = v * s;
            }
        }
        if let Some(r) = r {
            for (i, v) in r[b0..b0 + kb].iter().enumerate() {
                block[i * w + nf] = *v;
            }
        }
        for c0 in (0..nf).step_by(TI) {
            // w is a whole number of TJ (so of TI) tiles: every tile lies within a row
            for d0 in ((c0 / TJ) * TJ..w).step_by(TJ) {
                tile(&block, w, kb, c0, d0, &mut acc);
            }
        }
        b0 += kb;
    }
    for c in 0..nf {
        for d in c..nf {
            af[(c, d)] = acc[c * w + d];
            af[(d, c)] = acc[c * w + d];
        }
        if r.is_some() {
            gf[c] = acc[c * w + nf];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product against a plain triple loop, on shapes that leave partial tiles and blocks.
    #[test]
    fn gram_matches_the_plain_sums() {
        for (m, n, free) in [
            (130, 9, vec![0, 2, 3, 5, 8]),
            (70, 13, (0..13).collect::<Vec<_>>()),
            (5, 3, vec![1]),
            (40, 8, (0..8).collect()),
        ] {
            let j = DMatrix::from_fn(m, n, |i, k| ((i * 7 + k * 11) % 23) as f64 / 23.0 - 0.3);
            let s: Vec<f64> = (0..m).map(|i| 0.5 + (i % 5) as f64 * 0.25).collect();
            let r: Vec<f64> = (0..m).map(|i| (i as f64 * 0.3).sin()).collect();
            let nf = free.len();
            let rows = 3..m;
            // the path this machine takes, and the portable one
            let (mut af, mut gf) = (DMatrix::zeros(nf, nf), DVector::zeros(nf));
            let (mut af_portable, mut gf_portable) = (DMatrix::zeros(nf, nf), DVector::zeros(nf));
            weighted_gram_of_rows(&j, &free, &s, Some(&r), rows.clone(), &mut af, &mut gf);
            gram(
                &j,
                &free,
                &s,
                Some(&r),
                rows.clone(),
                &mut af_portable,
                &mut gf_portable,
                tile_portable,
            );
            for (af, gf) in [(&af, &gf), (&af_portable, &gf_portable)] {
                for (c, &k) in free.iter().enumerate() {
                    let g: f64 = rows.clone().map(|i| j[(i, k)] * s[i] * r[i]).sum();
                    assert!((gf[c] - g).abs() < 1e-12 * (1.0 + g.abs()), "g[{c}]");
                    for (d, &l) in free.iter().enumerate() {
                        let a: f64 = rows
                            .clone()
                            .map(|i| j[(i, k)] * j[(i, l)] * s[i] * s[i])
                            .sum();
                        assert!(
                            (af[(c, d)] - a).abs() < 1e-12 * (1.0 + a.abs()),
                            "A[{c}, {d}]: {} against {a}",
                            af[(c, d)]
                        );
                    }
                }
            }
        }
    }
}
