//! Adaptive (local mean) thresholding, as OpenCV's `adaptiveThreshold(ADAPTIVE_THRESH_MEAN_C,
//! THRESH_BINARY_INV)`: a pixel is foreground (dark ink) when I ≤ mean_window − C.
//!
//! Box sums come from running column sums (one row added, one removed per output row) and a
//! prefix sum along the row, as a separable box filter does: everything a row needs stays in
//! cache, where a whole-image integral table would stream 4 bytes per pixel from memory for
//! every window.

use image::GrayImage;

/// Binary mask (1 = foreground/dark, 0 = background) from a local-mean threshold with an odd
/// `window` and constant `c` (grey levels). Windows are clipped at the image border (mean of the
/// pixels inside). Integer test: I·n ≤ Σ − C·n, with C rounded to 1/16 grey level.
pub fn adaptive_threshold_mean(img: &GrayImage, window: u32, c: f64) -> Vec<u8> {
    let mut out = Vec::new();
    adaptive_threshold_mean_into(img, window, c, &mut out);
    out
}

/// As `adaptive_threshold_mean`, into a reused output buffer.
pub fn adaptive_threshold_mean_into(img: &GrayImage, window: u32, c: f64, out: &mut Vec<u8>) {
    // The default x86-64 target stops at SSE2 (4 × 32-bit lanes, no 32-bit multiply); the same
    // loops compiled for AVX2 run 8 lanes wide. Chosen at run time, so the binary stays portable.
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { threshold_avx2(img, window, c, out) };
        return;
    }
    threshold_portable(img, window, c, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn threshold_avx2(img: &GrayImage, window: u32, c: f64, out: &mut Vec<u8>) {
    threshold_portable(img, window, c, out);
}

#[inline(always)]
fn threshold_portable(img: &GrayImage, window: u32, c: f64, out: &mut Vec<u8>) {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let r = (window / 2) as usize;
    let raw = img.as_raw();
    let c16 = (c * 16.0).round() as i64;
    out.clear();
    out.reserve(w * h);
    // col[x] = Σ of column x over the rows [top, bot); u32 is exact for any window (the
    // differences below wrap exactly as long as a box sum stays below 2³²).
    let mut col = vec![0u32; w];
    let mut prefix = vec![0u32; w + 1];
    let (mut top, mut bot) = (0usize, 0usize);
    // i32 interior test: 16·255·n and 16·Σ stay below 2³¹ for windows up to 101 px.
    let narrow = window <= 101;
    for y in 0..h {
        let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(h));
        if bot < y1 && top < y0 {
            // Steady state: slide by one row in a single pass.
            let (add, sub) = (&raw[bot * w..(bot + 1) * w], &raw[top * w..(top + 1) * w]);
            for ((s, &a), &b) in col.iter_mut().zip(add).zip(sub) {
                *s = s.wrapping_add(a as u32).wrapping_sub(b as u32);
            }
            bot += 1;
            top += 1;
        }
        while bot < y1 {
            for (s, &a) in col.iter_mut().zip(&raw[bot * w..(bot + 1) * w]) {
                *s += a as u32;
            }
            bot += 1;
        }
        while top < y0 {
            for (s, &b) in col.iter_mut().zip(&raw[top * w..(top + 1) * w]) {
                *s = s.wrapping_sub(b as u32);
            }
            top += 1;
        }
        prefix_sums(&col, &mut prefix);
        let row = &raw[y * w..(y + 1) * w];
        let hgt = (y1 - y0) as i64;
        let test = |x: usize, x0: usize, x1: usize| {
            let sum = prefix[x1].wrapping_sub(prefix[x0]) as i64;
            let n = (x1 - x0) as i64 * hgt;
            (16 * row[x] as i64 * n <= 16 * sum - c16 * n) as u8
        };
        if w <= 2 * r + 1 || !narrow {
            out.extend((0..w).map(|x| test(x, x.saturating_sub(r), (x + r + 1).min(w))));
            continue;
        }
        out.extend((0..r).map(|x| test(x, 0, x + r + 1)));
        // Interior: constant n; equal-length slices so it vectorises. n < 2¹⁵ (window ≤ 101), and
        // saying so with an i16 lets the compiler use a 16-bit multiply-add for px·n.
        let n16 = ((2 * r + 1) * (y1 - y0)) as i16;
        let n = n16 as i32;
        let cn = (c16 as i32) * n;
        let m = w - 2 * r;
        let (lo, hi) = (&prefix[0..m], &prefix[2 * r + 1..2 * r + 1 + m]);
        out.extend(
            lo.iter()
                .zip(hi)
                .zip(&row[r..r + m])
                .map(|((&a, &b), &px)| {
                    (16 * (px as i16 as i32 * n16 as i32) <= 16 * b.wrapping_sub(a) as i32 - cn)
                        as u8
                }),
        );
        out.extend((w - r..w).map(|x| test(x, x - r, w)));
    }
}

/// prefix[k] = Σ col[0..k] (wrapping). A running sum is one chain of dependent additions (the
/// slowest part of the threshold when done one element at a time); on x86-64 four elements are
/// summed at once in a vector register (two shifted adds), then offset by the total so far.
#[inline(always)]
fn prefix_sums(col: &[u32], prefix: &mut [u32]) {
    assert_eq!(prefix.len(), col.len() + 1);
    prefix[0] = 0;
    #[cfg(not(target_arch = "x86_64"))]
    let (done, mut acc) = (0usize, 0u32);
    #[cfg(target_arch = "x86_64")]
    let (done, mut acc) = {
        use std::arch::x86_64::*;
        let mut done = 0usize;
        // SAFETY: SSE2 is part of the x86-64 baseline; every load reads col[i..i + 4] and every
        // store writes prefix[i + 1..i + 5] with i + 4 ≤ col.len() = prefix.len() − 1.
        unsafe {
            let mut carry = _mm_setzero_si128();
            while done + 4 <= col.len() {
                let mut x = _mm_loadu_si128(col.as_ptr().add(done) as *const __m128i);
                x = _mm_add_epi32(x, _mm_slli_si128(x, 4));
                x = _mm_add_epi32(x, _mm_slli_si128(x, 8));
                x = _mm_add_epi32(x, carry);
                _mm_storeu_si128(prefix.as_mut_ptr().add(done + 1) as *mut __m128i, x);
                carry = _mm_shuffle_epi32(x, 0xFF);
                done += 4;
            }
            (done, _mm_cvtsi128_si32(carry) as u32)
        }
    };
    for (p, &c) in prefix[done + 1..].iter_mut().zip(&col[done..]) {
        acc = acc.wrapping_add(c);
        *p = acc;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix_sums_of_any_length() {
        for w in 0..23usize {
            let col: Vec<u32> = (0..w as u32)
                .map(|k| k.wrapping_mul(2_654_435_761) % 1000)
                .collect();
            let mut got = vec![7u32; w + 1];
            prefix_sums(&col, &mut got);
            let expect: Vec<u32> = std::iter::once(0)
                .chain(col.iter().scan(0u32, |a, &c| {
                    *a += c;
                    Some(*a)
                }))
                .collect();
            assert_eq!(got, expect, "length {w}");
        }
    }

    #[test]
    fn matches_direct_mean_threshold() {
        let img = GrayImage::from_fn(37, 23, |x, y| {
            image::Luma([((x * 37 + y * 91) % 256) as u8])
        });
        for win in [3u32, 7, 13, 41] {
            let m = adaptive_threshold_mean(&img, win, 7.0);
            // Both paths, whatever the dispatch picks: the portable loop and, where the CPU has
            // it, the AVX2 build of the same loop, each against the direct mean below.
            let mut portable = Vec::new();
            threshold_portable(&img, win, 7.0, &mut portable);
            assert_eq!(
                portable, m,
                "win {win}: portable and dispatched paths differ"
            );
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                let mut avx2 = Vec::new();
                // SAFETY: the CPU supports AVX2 (checked just above).
                unsafe { threshold_avx2(&img, win, 7.0, &mut avx2) };
                assert_eq!(avx2, portable, "win {win}: AVX2 and portable paths differ");
            } else {
                eprintln!("matches_direct_mean_threshold: this CPU has no AVX2; only the portable path was checked");
            }
            let r = (win / 2) as i64;
            for y in 0..23i64 {
                for x in 0..37i64 {
                    let (mut s, mut n) = (0f64, 0f64);
                    for yy in (y - r).max(0)..=(y + r).min(22) {
                        for xx in (x - r).max(0)..=(x + r).min(36) {
                            s += img.get_pixel(xx as u32, yy as u32)[0] as f64;
                            n += 1.0;
                        }
                    }
                    let expect = (img.get_pixel(x as u32, y as u32)[0] as f64 <= s / n - 7.0) as u8;
                    assert_eq!(m[(y * 37 + x) as usize], expect, "win {win} at ({x},{y})");
                }
            }
        }
    }
}
