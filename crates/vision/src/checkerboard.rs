//! Checkerboard inner-corner detection: saddle-point candidates from the Hessian of a smoothed
//! image, a grid grown from a seed by extrapolation, then sub-pixel refinement of every corner
//! with the crossing-edges fit of `saddle_fit`.
//!
//! Output order: row-major; the column axis is the grid axis holding `cols` corners, oriented
//! to increase with image x, and the row axis turns clockwise from it on screen (so a frontal
//! board comes out top-left first, like the renderer's truth). When cols == rows, the column
//! axis is the grid axis closer to image x.

use crate::error::{invalid, Result, VisionError};
use crate::filters::gaussian_blur_f64;
use crate::saddle_fit::{refine_saddle, SaddleCorner};
use image::GrayImage;
use nalgebra::{Point2, Vector2};
use std::collections::HashMap;

/// Detected board: `cols` × `rows` inner corners, row-major.
#[derive(Debug, Clone)]
pub struct CheckerboardCorners {
    pub cols: usize,
    pub rows: usize,
    pub corners: Vec<SaddleCorner>,
}

impl CheckerboardCorners {
    pub fn point(&self, col: usize, row: usize) -> Point2<f64> {
        self.corners[row * self.cols + col].position
    }
}

/// Saddle-point candidates: local maxima of −det(Hessian) of the image smoothed with σ = `sigma`.
pub fn saddle_candidates(img: &GrayImage, sigma: f64) -> Vec<(Point2<f64>, f64)> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let src: Vec<f64> = img.as_raw().iter().map(|&v| v as f64).collect();
    let g = gaussian_blur_f64(&src, w, h, sigma);
    let mut resp = vec![0.0; w * h];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let ixx = g[i - 1] - 2.0 * g[i] + g[i + 1];
            let iyy = g[i - w] - 2.0 * g[i] + g[i + w];
            let ixy = 0.25 * (g[i - w - 1] + g[i + w + 1] - g[i - w + 1] - g[i + w - 1]);
            resp[i] = (ixy * ixy - ixx * iyy).max(0.0);
        }
    }
    let max = resp.iter().cloned().fold(0.0, f64::max);
    if max <= 0.0 {
        return Vec::new();
    }
    let thr = 0.05 * max;
    let r = 2usize;
    let mut out = Vec::new();
    for y in r + 1..h.saturating_sub(r + 1) {
        for x in r + 1..w.saturating_sub(r + 1) {
            let v = resp[y * w + x];
            if v < thr {
                continue;
            }
            let is_max = (y - r..=y + r).all(|yy| {
                (x - r..=x + r).all(|xx| {
                    resp[yy * w + xx] < v
                        || (xx == x && yy == y)
                        || (resp[yy * w + xx] == v && (yy, xx) > (y, x))
                })
            });
            if is_max && is_x_junction(&g, w, h, x as f64, y as f64, 4.0) {
                out.push((Point2::new(x as f64, y as f64), v));
            }
        }
    }
    out
}

/// True when a ring of radius `r` around (x, y) crosses the ring's mean level exactly four times
/// (an X-junction of four alternating squares), which rejects the T- and L-junctions along the
/// board's outline that also have a saddle-like Hessian.
fn is_x_junction(g: &[f64], w: usize, h: usize, x: f64, y: f64, r: f64) -> bool {
    const N: usize = 32;
    let mut vals = [0.0; N];
    for (k, v) in vals.iter_mut().enumerate() {
        let a = 2.0 * std::f64::consts::PI * k as f64 / N as f64;
        let (px, py) = (x + r * a.cos(), y + r * a.sin());
        if px < 0.0 || py < 0.0 || px > (w - 1) as f64 || py > (h - 1) as f64 {
            return false;
        }
        let (x0, y0) = (px.floor() as usize, py.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = (px - x0 as f64, py - y0 as f64);
        *v = (g[y0 * w + x0] * (1.0 - fx) + g[y0 * w + x1] * fx) * (1.0 - fy)
            + (g[y1 * w + x0] * (1.0 - fx) + g[y1 * w + x1] * fx) * fy;
    }
    let mean = vals.iter().sum::<f64>() / N as f64;
    let changes = (0..N)
        .filter(|&k| (vals[k] > mean) != (vals[(k + 1) % N] > mean))
        .count();
    changes == 4
}

/// Find the `cols` × `rows` inner corners of a checkerboard.
pub fn detect_checkerboard(
    img: &GrayImage,
    cols: usize,
    rows: usize,
) -> Result<CheckerboardCorners> {
    if cols < 2 || rows < 2 {
        return Err(invalid(
            "cols/rows",
            format!("need at least 2×2 inner corners, got {cols}×{rows}"),
        ));
    }
    if img.width() < 16 || img.height() < 16 {
        return Err(VisionError::ImageTooSmall {
            what: "detect_checkerboard input",
            width: img.width(),
            height: img.height(),
        });
    }
    let mut cands = saddle_candidates(img, 1.5);
    cands.sort_by(|a, b| b.1.total_cmp(&a.1));
    let pts: Vec<Point2<f64>> = cands.iter().map(|c| c.0).collect();
    let seeds = pts.len().min(30);
    // the largest lattice seen (columns, rows of its bounding box, points), for the reason
    let mut largest = (0usize, 0usize, 0usize);
    for seed in 0..seeds {
        let Some(grid) = grow_grid(&pts, seed).map(unshear) else {
            continue;
        };
        let span = |f: fn(&(i32, i32)) -> i32| {
            grid.keys()
                .map(f)
                .max()
                .zip(grid.keys().map(f).min())
                .map_or(0, |(hi, lo)| (hi - lo + 1) as usize)
        };
        if grid.len() > largest.2 {
            let (a, b) = (span(|k| k.0), span(|k| k.1));
            largest = (a.max(b), a.min(b), grid.len());
        }
        let Some(ordered) = orient(&grid, cols, rows) else {
            continue;
        };
        return Ok(CheckerboardCorners {
            cols,
            rows,
            corners: refine_board(img, &ordered, cols, rows)?,
        });
    }
    Err(VisionError::NoSolution {
        what: "detect_checkerboard",
        reason: not_found_reason(pts.len(), largest, cols, rows),
    })
}

/// Why no cols × rows board was found, with what to check.
fn not_found_reason(
    candidates: usize,
    largest: (usize, usize, usize),
    cols: usize,
    rows: usize,
) -> String {
    let needed = cols * rows;
    let (a, b, n) = largest;
    let lattice = if n >= 4 {
        format!("; the largest lattice of them spans {a}×{b} ({n} points)")
    } else {
        String::new()
    };
    if candidates < needed {
        return format!(
            "only {candidates} points look like inner corners (X-junctions of four squares), a {cols}×{rows} board has {needed}{lattice}: is the whole board in the frame, in focus and evenly lit, with squares of at least ~8 px? (--board counts inner corners: squares − 1 along each side)"
        );
    }
    format!("{candidates} points look like inner corners but no {cols}×{rows} lattice of them was found{lattice}: check --board (inner corners: squares − 1 along each side), or the board is seen too obliquely or partly hidden")
}

/// Sub-pixel refinement of every corner of an ordered board with its local grid directions.
fn refine_board(
    img: &GrayImage,
    ordered: &[Point2<f64>],
    cols: usize,
    rows: usize,
) -> Result<Vec<SaddleCorner>> {
    let mut corners = Vec::with_capacity(cols * rows);
    for r in 0..rows {
        for c in 0..cols {
            let p = ordered[r * cols + c];
            let nb = |dc: isize, dr: isize| -> Option<Point2<f64>> {
                let (cc, rr) = (c as isize + dc, r as isize + dr);
                (cc >= 0 && rr >= 0 && (cc as usize) < cols && (rr as usize) < rows)
                    .then(|| ordered[rr as usize * cols + cc as usize])
            };
            let du = nb(1, 0)
                .map(|q| q - p)
                .or_else(|| nb(-1, 0).map(|q| p - q))
                .unwrap();
            let dv = nb(0, 1)
                .map(|q| q - p)
                .or_else(|| nb(0, -1).map(|q| p - q))
                .unwrap();
            let radius = 0.4 * du.norm().min(dv.norm());
            let refined = refine_saddle(img, p, [du.x, du.y], [dv.x, dv.y], radius).ok_or_else(|| VisionError::NoSolution {
                what: "checkerboard corner refinement",
                reason: format!(
                    "corner (col {c}, row {r}) near ({:.1}, {:.1}): the fit of two crossing edges within {radius:.1} px did not settle (glare, a smudge or strong blur there, or squares under ~8 px)",
                    p.x, p.y
                ),
            })?;
            corners.push(refined);
        }
    }
    Ok(corners)
}

/// Grow an integer grid (i, j) → point from candidate `seed` by linear extrapolation.
fn grow_grid(pts: &[Point2<f64>], seed: usize) -> Option<HashMap<(i32, i32), Point2<f64>>> {
    let s = pts[seed];
    let mut by_dist: Vec<(f64, usize)> = pts
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != seed)
        .map(|(k, p)| ((p - s).norm(), k))
        .collect();
    by_dist.sort_by(|a, b| a.0.total_cmp(&b.0));
    let u = pts[by_dist.first()?.1] - s;
    let v = by_dist
        .iter()
        .skip(1)
        .take(6)
        .map(|&(_, k)| pts[k] - s)
        .find(|d| (d.dot(&u) / (d.norm() * u.norm())).abs() < 0.5)?;
    let mut grid: HashMap<(i32, i32), Point2<f64>> = HashMap::new();
    let mut used = vec![false; pts.len()];
    grid.insert((0, 0), s);
    used[seed] = true;
    let mut queue = vec![(0i32, 0i32)];
    let nearest = |pred: Point2<f64>, tol: f64, used: &Vec<bool>| -> Option<usize> {
        pts.iter()
            .enumerate()
            .filter(|(k, p)| !used[*k] && (*p - pred).norm() < tol)
            .min_by(|a, b| (a.1 - pred).norm().total_cmp(&(b.1 - pred).norm()))
            .map(|(k, _)| k)
    };
    while let Some((i, j)) = queue.pop() {
        let p = grid[&(i, j)];
        for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let key = (i + di, j + dj);
            if grid.contains_key(&key) {
                continue;
            }
            // Step: from the opposite neighbour if known, else from the seed basis.
            let step: Vector2<f64> = match grid.get(&(i - di, j - dj)) {
                Some(q) => p - q,
                None => {
                    // try a parallel step in an adjacent row/column
                    let (oi, oj) = (dj.abs(), di.abs());
                    [(oi, oj), (-oi, -oj)]
                        .iter()
                        .find_map(|&(a, b)| {
                            Some(grid.get(&(i + di + a, j + dj + b))? - grid.get(&(i + a, j + b))?)
                        })
                        .unwrap_or(if di != 0 {
                            u * di as f64
                        } else {
                            v * dj as f64
                        })
                }
            };
            let pred = p + step;
            if let Some(k) = nearest(pred, 0.3 * step.norm(), &used) {
                used[k] = true;
                grid.insert(key, pts[k]);
                queue.push(key);
            }
        }
    }
    Some(grid)
}

/// The grid in rectangular lattice coordinates. Under strong perspective the seed's nearest
/// non-parallel neighbour can be a diagonal one: the grid then grows right but in sheared
/// coordinates (a 9 × 6 board spans 14 × 6 keys). A shear (i, j) → (i − k·j, j) or
/// (i, j − k·i), |k| ≤ 3, whose keys fill their bounding box is taken; else the grid as it is.
fn unshear(grid: HashMap<(i32, i32), Point2<f64>>) -> HashMap<(i32, i32), Point2<f64>> {
    let fills = |g: &HashMap<(i32, i32), Point2<f64>>| {
        let span = |f: fn(&(i32, i32)) -> i32| {
            g.keys()
                .map(f)
                .max()
                .zip(g.keys().map(f).min())
                .map_or(0, |(hi, lo)| (hi - lo + 1) as usize)
        };
        span(|k| k.0) * span(|k| k.1) == g.len()
    };
    if fills(&grid) {
        return grid;
    }
    for k in [1, -1, 2, -2, 3, -3] {
        for along_i in [true, false] {
            let sheared: HashMap<(i32, i32), Point2<f64>> = grid
                .iter()
                .map(|(&(i, j), &p)| {
                    (
                        if along_i {
                            (i - k * j, j)
                        } else {
                            (i, j - k * i)
                        },
                        p,
                    )
                })
                .collect();
            if fills(&sheared) {
                return sheared;
            }
        }
    }
    grid
}

/// Order the grid row-major as documented, if it is exactly cols × rows (or rows × cols).
fn orient(
    grid: &HashMap<(i32, i32), Point2<f64>>,
    cols: usize,
    rows: usize,
) -> Option<Vec<Point2<f64>>> {
    let (imin, imax) = (
        grid.keys().map(|k| k.0).min()?,
        grid.keys().map(|k| k.0).max()?,
    );
    let (jmin, jmax) = (
        grid.keys().map(|k| k.1).min()?,
        grid.keys().map(|k| k.1).max()?,
    );
    let (ni, nj) = ((imax - imin + 1) as usize, (jmax - jmin + 1) as usize);
    if grid.len() != ni * nj {
        return None;
    }
    let at = |i: i32, j: i32| grid[&(i + imin, j + jmin)];
    // Mean axis vectors of grid i and j.
    let ai = at(ni as i32 - 1, 0) - at(0, 0);
    let aj = at(0, nj as i32 - 1) - at(0, 0);
    let i_is_col = if ni == nj {
        if ni != cols || cols != rows {
            return None;
        }
        ai.x.abs() / ai.norm() >= aj.x.abs() / aj.norm()
    } else if (ni, nj) == (cols, rows) {
        true
    } else if (ni, nj) == (rows, cols) {
        false
    } else {
        return None;
    };
    // Map (c, r) → (i, j) with signs.
    let (col_axis, row_axis) = if i_is_col { (ai, aj) } else { (aj, ai) };
    let flip_c = col_axis.x < 0.0 || (col_axis.x == 0.0 && col_axis.y < 0.0);
    let col_dir = if flip_c { -col_axis } else { col_axis };
    let cross = col_dir.x * row_axis.y - col_dir.y * row_axis.x;
    let flip_r = cross < 0.0;
    let mut out = Vec::with_capacity(cols * rows);
    for r in 0..rows as i32 {
        for c in 0..cols as i32 {
            let cc = if flip_c { cols as i32 - 1 - c } else { c };
            let rr = if flip_r { rows as i32 - 1 - r } else { r };
            let (i, j) = if i_is_col { (cc, rr) } else { (rr, cc) };
            out.push(at(i, j));
        }
    }
    Some(out)
}
