//! Adaptive (local mean) thresholding, as OpenCV's `adaptiveThreshold(ADAPTIVE_THRESH_MEAN_C,
//! THRESH_BINARY_INV)`: a pixel is foreground (dark ink) when I ≤ mean_window − C.

use image::GrayImage;

/// Summed-area table with a zero first row/column: entry (x, y) = Σ of pixels with x' < x, y' < y.
/// u32 suffices: 255 · 3840 · 2160 < 2³², and wrapping arithmetic keeps box sums exact below 2³².
pub struct IntegralImage {
    w: usize,
    sums: Vec<u32>,
}

impl IntegralImage {
    pub fn new(img: &GrayImage) -> Self {
        let (w, h) = (img.width() as usize, img.height() as usize);
        let raw = img.as_raw();
        let stride = w + 1;
        let mut sums = vec![0u32; stride * (h + 1)];
        for y in 0..h {
            let mut row = 0u32;
            let src = &raw[y * w..(y + 1) * w];
            let (prev, cur) = sums.split_at_mut((y + 1) * stride);
            let prev = &prev[y * stride..];
            for x in 0..w {
                row = row.wrapping_add(src[x] as u32);
                cur[x + 1] = prev[x + 1].wrapping_add(row);
            }
        }
        Self { w, sums }
    }
}

/// Binary mask (1 = foreground/dark, 0 = background) from a local-mean threshold with an odd
/// `window` and constant `c` (grey levels). Windows are clipped at the image border (mean of the
/// pixels inside). Integer test: I·n ≤ Σ − C·n, with C rounded to 1/16 grey level.
pub fn adaptive_threshold_mean(img: &GrayImage, window: u32, c: f64) -> Vec<u8> {
    let mut out = Vec::new();
    adaptive_threshold_mean_into(img, &IntegralImage::new(img), window, c, &mut out);
    out
}

/// As `adaptive_threshold_mean`, with a precomputed integral image and a reused output buffer.
pub fn adaptive_threshold_mean_into(
    img: &GrayImage,
    integral: &IntegralImage,
    window: u32,
    c: f64,
    out: &mut Vec<u8>,
) {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let r = (window / 2) as usize;
    let raw = img.as_raw();
    let c16 = (c * 16.0).round() as i64;
    out.clear();
    out.resize(w * h, 0);
    let stride = w + 1;
    let s = &integral.sums;
    debug_assert_eq!(integral.w, w);
    for y in 0..h {
        let y0 = y.saturating_sub(r);
        let y1 = (y + r + 1).min(h);
        let (top, bot) = (
            &s[y0 * stride..y0 * stride + stride],
            &s[y1 * stride..y1 * stride + stride],
        );
        let row = &raw[y * w..(y + 1) * w];
        let orow = &mut out[y * w..(y + 1) * w];
        let hgt = (y1 - y0) as i64;
        let mut test = |x: usize, x0: usize, x1: usize| {
            let sum = bot[x1]
                .wrapping_add(top[x0])
                .wrapping_sub(top[x1])
                .wrapping_sub(bot[x0]) as i64;
            let n = (x1 - x0) as i64 * hgt;
            orow[x] = (16 * row[x] as i64 * n <= 16 * sum - c16 * n) as u8;
        };
        if w <= 2 * r + 1 {
            for x in 0..w {
                test(x, x.saturating_sub(r), (x + r + 1).min(w));
            }
            continue;
        }
        for x in 0..r {
            test(x, 0, x + r + 1);
        }
        for x in w - r..w {
            test(x, x - r, w);
        }
        // Interior: constant n; equal-length slices so it vectorises (no overflow: 16·255·n and
        // 16·Σ stay below 2³¹ for windows up to 101 px).
        let n = (2 * r + 1) as i32 * hgt as i32;
        let cn = (c16 as i32) * n;
        let m = w - 2 * r;
        let (bl, br) = (&bot[0..m], &bot[2 * r + 1..2 * r + 1 + m]);
        let (tl, tr) = (&top[0..m], &top[2 * r + 1..2 * r + 1 + m]);
        let px = &row[r..r + m];
        let o = &mut orow[r..r + m];
        for i in 0..m {
            let sum = br[i]
                .wrapping_add(tl[i])
                .wrapping_sub(tr[i])
                .wrapping_sub(bl[i]) as i32;
            o[i] = (16 * px[i] as i32 * n <= 16 * sum - cn) as u8;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_direct_mean_threshold() {
        let img = GrayImage::from_fn(37, 23, |x, y| {
            image::Luma([((x * 37 + y * 91) % 256) as u8])
        });
        for win in [3u32, 7, 13, 41] {
            let m = adaptive_threshold_mean(&img, win, 7.0);
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
