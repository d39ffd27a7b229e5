//! Drilled-hole plate (seed 000): a checkerboard of `squares_x` × `squares_y` squares with one
//! hole drilled at the centre of every square, over an inverse-contrast backing. The board's
//! inner corners give each hole's predicted pixel position, which assigns holes to grid cells;
//! [`crate::holes::measure_holes`] then measures each hole (ellipse moments, centroid, centre
//! covariance) in a window inside its square.
//!
//! Cell order: row-major over squares, cell id = row · squares_x + col, with the column and row
//! axes of [`crate::checkerboard`] (a frontal board: top-left square first). Square (c, r) is
//! bounded by inner corners (c−1, r−1) … (c, r); corners outside the inner grid (border squares)
//! are extrapolated linearly from the two nearest inner corners along each axis, which follows
//! lens distortion locally. The predicted centre is the intersection of the quad's diagonals,
//! the exact image of the square's centre under perspective.

use crate::checkerboard::detect_checkerboard;
use crate::error::{invalid, Result, VisionError};
use crate::holes::{measure_holes, HoleMeasurement, HoleRejection, HoleSearch};
use image::GrayImage;
use nalgebra::{Point2, Vector2};

/// One grid cell's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct GridHole {
    /// row · squares_x + col.
    pub cell: usize,
    /// Predicted centre from the board corners (px).
    pub predicted: Point2<f64>,
    pub result: std::result::Result<HoleMeasurement, HoleRejection>,
}

/// Predicted hole centres (px), row-major over squares, from the board's inner corners
/// (`(squares_x − 1) × (squares_y − 1)`, row-major), and the shortest side of each square (px).
pub fn predict_hole_centres(
    inner: &[Point2<f64>],
    squares_x: usize,
    squares_y: usize,
) -> Result<Vec<(Point2<f64>, f64)>> {
    let (cols, rows) = (squares_x.wrapping_sub(1), squares_y.wrapping_sub(1));
    if squares_x < 3 || squares_y < 3 || inner.len() != cols * rows {
        return Err(invalid("inner corners", format!("need (squares_x−1)×(squares_y−1) ≥ 2×2 corners, got {} for {squares_x}×{squares_y} squares", inner.len())));
    }
    // Corner grid extended by one on every side: index i in −1..=cols maps to an inner index
    // clamped into range plus a linear step.
    let at = |c: usize, r: usize| inner[r * cols + c].coords;
    let ext = |c: isize, r: isize| -> Vector2<f64> {
        let clamp = |k: isize, n: usize| k.clamp(0, n as isize - 1) as usize;
        let (cc, rc) = (clamp(c, cols), clamp(r, rows));
        let mut p = at(cc, rc);
        let dc = c - cc as isize; // −1, 0 or +1
        if dc != 0 {
            let nb = if dc < 0 {
                at(cc + 1, rc)
            } else {
                at(cc - 1, rc)
            };
            p += p - nb;
        }
        let dr = r - rc as isize;
        if dr != 0 {
            // Step along the row axis measured at the (clamped) column; with a corner both
            // steps apply (bilinear extrapolation).
            let nb = if dr < 0 {
                at(cc, rc + 1)
            } else {
                at(cc, rc - 1)
            };
            p += at(cc, rc) - nb;
        }
        p
    };
    let mut out = Vec::with_capacity(squares_x * squares_y);
    for r in 0..squares_y as isize {
        for c in 0..squares_x as isize {
            let (a, b, cq, d) = (ext(c - 1, r - 1), ext(c, r - 1), ext(c, r), ext(c - 1, r));
            // Diagonals a→cq and b→d: a + s(cq − a) = b + t(d − b).
            let (u, v, w) = (cq - a, d - b, b - a);
            let den = u.x * (-v.y) - u.y * (-v.x);
            if den.abs() < 1e-12 {
                return Err(VisionError::NoSolution {
                    what: "hole prediction",
                    reason: format!("square ({c}, {r}) is degenerate"),
                });
            }
            let s = (w.x * (-v.y) - w.y * (-v.x)) / den;
            let centre = a + u * s;
            let side = [
                (b - a).norm(),
                (cq - b).norm(),
                (d - cq).norm(),
                (a - d).norm(),
            ]
            .into_iter()
            .fold(f64::INFINITY, f64::min);
            out.push((Point2::from(centre), side));
        }
    }
    Ok(out)
}

/// Find the plate in `img` and measure every hole. `window_half_px` = 0 sizes each search
/// window to 0.3 × the square's shortest side, so the window stays inside its square (a clean
/// background) for holes up to about half the square. `Ok(None)` when no board is found.
pub fn detect_hole_grid(
    img: &GrayImage,
    squares_x: usize,
    squares_y: usize,
    search: &HoleSearch,
) -> Result<Option<Vec<GridHole>>> {
    if squares_x < 3 || squares_y < 3 {
        return Err(invalid("squares", format!("a hole plate needs at least 3×3 squares (2×2 inner corners), got {squares_x}×{squares_y}")));
    }
    let board = match detect_checkerboard(img, squares_x - 1, squares_y - 1) {
        Ok(b) => b,
        Err(VisionError::NoSolution { .. }) => return Ok(None),
        Err(e) => return Err(e),
    };
    let inner: Vec<Point2<f64>> = board.corners.iter().map(|c| c.position).collect();
    let predicted = predict_hole_centres(&inner, squares_x, squares_y)?;
    let mut out = Vec::with_capacity(predicted.len());
    for (cell, (p, side)) in predicted.into_iter().enumerate() {
        let window = if search.window_half_px == 0 {
            ((0.3 * side).floor() as u32).max(3)
        } else {
            search.window_half_px
        };
        let s = HoleSearch {
            window_half_px: window,
            ..*search
        };
        let result = measure_holes(img, &[p], &s)?
            .pop()
            .expect("one prediction, one result");
        out.push(GridHole {
            cell,
            predicted: p,
            result,
        });
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predictions_are_square_centres_including_extrapolated_border_squares() {
        // Affine grid: inner corner (c, r) at (100 + 20(c+1) + 2(r+1), 50 + 18(r+1)) for a 4×3-square board.
        let map = |x: f64, y: f64| Point2::new(100.0 + 20.0 * x + 2.0 * y, 50.0 + 18.0 * y);
        let inner: Vec<Point2<f64>> = (0..2)
            .flat_map(|r| (0..3).map(move |c| (c, r)))
            .map(|(c, r)| map(c as f64 + 1.0, r as f64 + 1.0))
            .collect();
        let p = predict_hole_centres(&inner, 4, 3).unwrap();
        assert_eq!(p.len(), 12);
        for r in 0..3 {
            for c in 0..4 {
                let want = map(c as f64 + 0.5, r as f64 + 0.5);
                let got = p[r * 4 + c].0;
                assert!(
                    (got - want).norm() < 1e-9,
                    "square ({c}, {r}): {got} vs {want}"
                );
            }
        }
        assert!(
            (p[0].1 - 2f64.hypot(18.0)).abs() < 1e-9,
            "shortest side {}",
            p[0].1
        );
        assert!(predict_hole_centres(&inner, 3, 3).is_err());
        assert!(detect_hole_grid(&GrayImage::new(64, 64), 2, 5, &HoleSearch::default()).is_err());
        assert_eq!(
            detect_hole_grid(
                &GrayImage::from_pixel(64, 64, image::Luma([128])),
                4,
                4,
                &HoleSearch::default()
            )
            .unwrap(),
            None
        );
    }
}
