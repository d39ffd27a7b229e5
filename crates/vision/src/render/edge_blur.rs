//! Gaussian blur computed only near edges. A pixel whose whole (2r + 1)² kernel window holds
//! no edge-mask pixel sees one region of constant grey (the window is a connected block that no
//! boundary crosses, see [`super::edges`]), and blurring a constant gives the constant back, so
//! only tiles within r of a marked pixel are filtered. Those are filtered exactly as
//! [`crate::filters::gaussian_blur_f64`] does (same kernel, same clamped edges, same summation
//! order), so the result equals the full blur there bit for bit.

use crate::filters::gaussian_kernel;

/// Blur `grey` (w×h, row-major) in place with standard deviation `sigma` px, given the edge
/// mask (1 = an edge may cross the pixel).
pub(super) fn blur_near_edges(grey: &mut [f64], mask: &[u8], w: usize, h: usize, sigma: f64) {
    let k = gaussian_kernel(sigma);
    let r = k.len() / 2;
    // Tiles at least r wide, so every pixel within r of a tile lies in its 3×3 neighbourhood.
    let tile = r.max(16);
    let (tw, th) = (w.div_ceil(tile), h.div_ceil(tile));
    let mut marked = vec![false; tw * th];
    for y in 0..h {
        let row = &mask[y * w..(y + 1) * w];
        for (tx, chunk) in row.chunks(tile).enumerate() {
            if chunk.contains(&1) {
                marked[(y / tile) * tw + tx] = true;
            }
        }
    }
    let active = |tx: usize, ty: usize| {
        (ty.saturating_sub(1)..(ty + 2).min(th))
            .any(|y| (tx.saturating_sub(1)..(tx + 2).min(tw)).any(|x| marked[y * tw + x]))
    };
    let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
    // Blurred tiles are kept aside until all are done: each reads its neighbours unblurred.
    let mut done: Vec<(usize, usize, usize, usize, Vec<f64>)> = Vec::new();
    let mut tmp = Vec::new();
    for ty in 0..th {
        for tx in 0..tw {
            if !active(tx, ty) {
                continue;
            }
            let (x0, x1) = (tx * tile, ((tx + 1) * tile).min(w));
            let (y0, y1) = (ty * tile, ((ty + 1) * tile).min(h));
            let (ya, yb) = (y0.saturating_sub(r), (y1 + r).min(h));
            let tw_px = x1 - x0;
            tmp.clear();
            tmp.resize((yb - ya) * tw_px, 0.0);
            // Interior pixels read their window directly; those within r of the image border
            // clamp each index. Either way the sum runs over the taps in order.
            for y in ya..yb {
                let src = &grey[y * w..(y + 1) * w];
                for x in x0..x1 {
                    let mut acc = 0.0;
                    if x >= r && x + r < w {
                        for (kv, v) in k.iter().zip(&src[x - r..=x + r]) {
                            acc += kv * v;
                        }
                    } else {
                        for (t, kv) in k.iter().enumerate() {
                            acc += kv * src[clamp(x as isize + t as isize - r as isize, w)];
                        }
                    }
                    tmp[(y - ya) * tw_px + x - x0] = acc;
                }
            }
            let mut out = vec![0.0; (y1 - y0) * tw_px];
            let mut acc = vec![0.0; tw_px];
            for y in y0..y1 {
                acc.fill(0.0);
                for (t, kv) in k.iter().enumerate() {
                    let row = clamp(y as isize + t as isize - r as isize, h) - ya;
                    for (a, v) in acc.iter_mut().zip(&tmp[row * tw_px..(row + 1) * tw_px]) {
                        *a += kv * v;
                    }
                }
                out[(y - y0) * tw_px..(y - y0 + 1) * tw_px].copy_from_slice(&acc);
            }
            done.push((x0, x1, y0, y1, out));
        }
    }
    for (x0, x1, y0, y1, out) in done {
        for y in y0..y1 {
            grey[y * w + x0..y * w + x1]
                .copy_from_slice(&out[(y - y0) * (x1 - x0)..(y - y0 + 1) * (x1 - x0)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filters::gaussian_blur_f64;

    #[test]
    fn equals_the_full_blur_on_a_piecewise_constant_image() {
        // Two regions split by a slanted edge; the mask marks every pixel next to the edge.
        let (w, h) = (97, 61);
        let side = |x: f64, y: f64| 0.3 * x + y - 40.0;
        let mut grey = vec![0.0; w * h];
        let mut mask = vec![0u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let (fx, fy) = (x as f64, y as f64);
                grey[y * w + x] = if side(fx, fy) < 0.0 { 20.0 } else { 235.0 };
                let corners = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)]
                    .map(|(dx, dy)| side(fx + dx, fy + dy) < 0.0);
                if corners.iter().any(|&c| c != corners[0]) {
                    mask[y * w + x] = 1;
                    grey[y * w + x] = 127.5;
                }
            }
        }
        for sigma in [0.8, 2.5, 5.0] {
            let full = gaussian_blur_f64(&grey, w, h, sigma);
            let mut near = grey.clone();
            blur_near_edges(&mut near, &mask, w, h, sigma);
            let worst = full
                .iter()
                .zip(&near)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-9, "σ = {sigma}: worst difference {worst}");
            assert!(near != grey, "σ = {sigma}: the edge was blurred");
        }
    }
}
