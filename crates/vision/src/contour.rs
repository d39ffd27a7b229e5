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
    let mut stack: Vec<usize> = Vec::new();
    let mut out = Vec::new();
    let mut start = 0usize;
    // Jump from unvisited foreground pixel to the next (fast scan over other values).
    while let Some(off) = mask[start..].iter().position(|&v| v == 1) {
        start += off;
        let seed = start;
        start += 1;
        mask[seed] = 2;
        stack.push(seed);
        let (mut xmin, mut xmax, mut ymin, mut ymax) = (w, 0, h, 0);
        let mut area = 0usize;
        while let Some(p) = stack.pop() {
            area += 1;
            let (x, y) = (p % w, p / w);
            xmin = xmin.min(x);
            xmax = xmax.max(x);
            ymin = ymin.min(y);
            ymax = ymax.max(y);
            if x > 0 && y > 0 && x + 1 < w && y + 1 < h {
                // interior: no bounds checks
                for q in [
                    p - w - 1,
                    p - w,
                    p - w + 1,
                    p - 1,
                    p + 1,
                    p + w - 1,
                    p + w,
                    p + w + 1,
                ] {
                    if mask[q] == 1 {
                        mask[q] = 2;
                        stack.push(q);
                    }
                }
            } else {
                for (dx, dy) in DIRS {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                        continue;
                    }
                    let q = ny as usize * w + nx as usize;
                    if mask[q] == 1 {
                        mask[q] = 2;
                        stack.push(q);
                    }
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
