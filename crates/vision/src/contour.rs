//! Outer boundaries of 8-connected foreground components (what `findContours` returns for
//! outer borders), by flood-fill labelling and Moore-neighbour tracing.

/// One component's outer boundary, pixel coordinates in tracing order (clockwise on screen).
#[derive(Debug, Clone)]
pub struct Contour {
    pub points: Vec<(i32, i32)>,
    /// Number of pixels in the component.
    pub area: usize,
}

/// Moore neighbourhood, clockwise on screen (y down), starting west.
const DIRS: [(i32, i32); 8] = [
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
];

/// Outer contours of all components of `mask` (0 = background, 1 = foreground, as
/// `threshold::adaptive_threshold_mean` produces) whose bounding-box
/// half-perimeter lies in [min_half_perimeter, max_half_perimeter]. Visited pixels are marked
/// by setting them to 2 in `mask` (no separate label image: any foreground pixel 8-adjacent to a
/// component belongs to it, so tracing only needs "foreground or not").
pub fn outer_contours(
    mask: &mut [u8],
    w: usize,
    h: usize,
    min_half_perimeter: usize,
    max_half_perimeter: usize,
) -> Vec<Contour> {
    // Spans (row, first x, last x) of the component still to be expanded.
    let mut stack: Vec<(usize, usize, usize)> = Vec::new();
    let mut out = Vec::new();
    let mut start = 0usize;
    while let Some(seed) = next_unvisited(mask, start) {
        start = seed + 1;
        let (sy, sx) = (seed / w, seed % w);
        stack.push(claim_run(&mut mask[sy * w..(sy + 1) * w], sx, sy));
        let (mut xmin, mut xmax, mut ymin, mut ymax) = (w, 0, h, 0);
        let mut area = 0usize;
        // Scanline fill: whole runs are claimed at once, so the cost grows with the number of
        // runs rather than of pixels (marker interiors are large dark blobs).
        while let Some((y, x0, x1)) = stack.pop() {
            area += x1 - x0 + 1;
            xmin = xmin.min(x0);
            xmax = xmax.max(x1);
            ymin = ymin.min(y);
            ymax = ymax.max(y);
            // 8-connectivity: runs in the rows above and below touching [x0 − 1, x1 + 1].
            let (lo, hi) = (x0.saturating_sub(1), (x1 + 1).min(w - 1));
            for ny in [y.wrapping_sub(1), y + 1] {
                if ny >= h {
                    continue;
                }
                let row = &mut mask[ny * w..(ny + 1) * w];
                let mut x = lo;
                while let Some(found) = next_unvisited(&row[..=hi], x) {
                    let run = claim_run(row, found, ny);
                    x = run.2 + 2; // run.2 + 1 is not foreground-unvisited
                    stack.push(run);
                }
            }
        }
        let half = (xmax - xmin + 1) + (ymax - ymin + 1);
        if half < min_half_perimeter || half > max_half_perimeter {
            continue;
        }
        // `seed` is the first pixel in raster order: its west and north neighbours are background.
        let points = trace(mask, w, h, seed);
        out.push(Contour { points, area });
    }
    out
}

/// Mark the run of unvisited foreground through `row[x]` as visited; returns (y, first, last).
fn claim_run(row: &mut [u8], x: usize, y: usize) -> (usize, usize, usize) {
    let mut a = x;
    while a > 0 && row[a - 1] == 1 {
        a -= 1;
    }
    let b = next_not_unvisited(row, x + 1).unwrap_or(row.len()) - 1;
    row[a..=b].fill(2);
    (y, a, b)
}

// The scans below read eight mask bytes at a time. The mask holds only 0, 1 and 2, so bit 0 of
// a byte is set exactly for 1 (unvisited foreground), and bits 0–1 of byte ^ 1 are zero exactly
// for 1.
const LOW_BITS: u64 = 0x0101_0101_0101_0101;

/// First index ≥ `from` whose byte makes `hit(word)` set that byte's bit 0, if any.
#[inline]
fn scan(mask: &[u8], from: usize, hit: impl Fn(u64) -> u64) -> Option<usize> {
    let rest = mask.get(from..)?;
    let word = |c: &[u8]| hit(u64::from_le_bytes(c.try_into().unwrap())) & LOW_BITS;
    // 32 bytes per step while nothing is found (long stretches of background or visited
    // pixels), then the word, then the byte.
    let mut i = 0;
    while i + 32 <= rest.len() {
        let c = &rest[i..i + 32];
        if word(&c[0..8]) | word(&c[8..16]) | word(&c[16..24]) | word(&c[24..32]) != 0 {
            break;
        }
        i += 32;
    }
    while i + 8 <= rest.len() {
        let v = word(&rest[i..i + 8]);
        if v != 0 {
            return Some(from + i + v.trailing_zeros() as usize / 8);
        }
        i += 8;
    }
    // Fewer than 8 bytes left: one byte at a time (hit() looks at bit 0 of each byte only).
    (i..rest.len())
        .find(|&k| hit(rest[k] as u64) & 1 != 0)
        .map(|k| from + k)
}

/// Index of the first unvisited foreground pixel (value 1) at or after `from`.
fn next_unvisited(mask: &[u8], from: usize) -> Option<usize> {
    scan(mask, from, |v| v)
}

/// Index of the first pixel at or after `from` that is not unvisited foreground.
fn next_not_unvisited(mask: &[u8], from: usize) -> Option<usize> {
    scan(mask, from, |v| {
        let x = v ^ LOW_BITS;
        x | (x >> 1)
    })
}

/// Moore-neighbour tracing of the component holding `start`, its raster-first pixel.
fn trace(mask: &[u8], w: usize, h: usize, start: usize) -> Vec<(i32, i32)> {
    let inside = |x: i32, y: i32| {
        x >= 0 && y >= 0 && x < w as i32 && y < h as i32 && mask[y as usize * w + x as usize] != 0
    };
    let s = ((start % w) as i32, (start / w) as i32);
    let mut pts = vec![s];
    // Backtrack direction: we "came from" the west neighbour (background).
    let mut cur = s;
    let mut back = 0usize; // index in DIRS of the backtrack neighbour
    let mut first_move: Option<((i32, i32), usize)> = None;
    let max_steps = 4 * w * h;
    for _ in 0..max_steps {
        // search clockwise from the backtrack position
        let mut found = None;
        for k in 1..=8 {
            let d = (back + k) % 8;
            let (nx, ny) = (cur.0 + DIRS[d].0, cur.1 + DIRS[d].1);
            if inside(nx, ny) {
                found = Some((d, (nx, ny)));
                break;
            }
        }
        let Some((d, nxt)) = found else { return pts }; // isolated pixel
                                                        // new backtrack: the neighbour examined just before `d`, seen from `nxt`
        let prev = (d + 7) % 8;
        let bp = (cur.0 + DIRS[prev].0, cur.1 + DIRS[prev].1);
        let nb = DIRS
            .iter()
            .position(|&(dx, dy)| (nxt.0 + dx, nxt.1 + dy) == bp)
            .unwrap_or((d + 4) % 8);
        // Jacob's stopping criterion: back at start entering the same way as the first move.
        if let Some(fm) = first_move {
            if cur == s && (nxt, d) == fm {
                pts.pop();
                return pts;
            }
        } else {
            first_move = Some((nxt, d));
        }
        pts.push(nxt);
        cur = nxt;
        back = nb;
    }
    pts
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Components (raster-first pixel, area) by a plain per-pixel 8-connected flood fill.
    fn reference_components(mask: &[u8], w: usize, h: usize) -> Vec<((i32, i32), usize)> {
        let mut seen = vec![false; w * h];
        let mut out = Vec::new();
        for seed in 0..w * h {
            if mask[seed] != 1 || seen[seed] {
                continue;
            }
            seen[seed] = true;
            let (mut stack, mut area) = (vec![seed], 0);
            while let Some(p) = stack.pop() {
                area += 1;
                let (x, y) = ((p % w) as i32, (p / w) as i32);
                for (dx, dy) in DIRS {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h {
                        let q = ny as usize * w + nx as usize;
                        if mask[q] == 1 && !seen[q] {
                            seen[q] = true;
                            stack.push(q);
                        }
                    }
                }
            }
            out.push((((seed % w) as i32, (seed / w) as i32), area));
        }
        out
    }

    #[test]
    fn components_match_pixelwise_flood_fill() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for (w, h, density) in [(61, 47, 0.45), (64, 9, 0.6), (13, 70, 0.3), (200, 3, 0.7)] {
            let mask: Vec<u8> = (0..w * h).map(|_| rng.random_bool(density) as u8).collect();
            let expect = reference_components(&mask, w, h);
            let mut m = mask.clone();
            let got: Vec<_> = outer_contours(&mut m, w, h, 0, usize::MAX)
                .into_iter()
                .map(|c| (c.points[0], c.area))
                .collect();
            assert_eq!(got, expect, "{w}×{h} density {density}");
            assert!(m.iter().all(|&v| v != 1), "every foreground pixel visited");
        }
    }
}
