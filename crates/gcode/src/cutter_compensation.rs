//! Cutter radius compensation (G41 left, G42 right, as ISO 6983 and every controller spell it)
//! on a closed contour of straight moves: the path of the tool's centre, each side of the
//! programmed contour offset by the radius and neighbouring sides meeting at their intersection
//! (sharp corners stay sharp, as controllers do for inside corners).
//!
//! Seed 004 measured an 18 mm square where a 20 mm pocket was programmed and blamed the 2 mm
//! cutter: the part program gave the pocket's wall, the machine drove the tool's centre on it
//! (no compensation), so every wall moved in by the radius. This is the centre path a
//! compensated program drives.

/// Which side of the direction of travel the tool runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CutterSide {
    /// G41: the tool left of the contour.
    Left,
    /// G42: the tool right of the contour.
    Right,
}

/// Why no centre path exists.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CutterError {
    #[error("a closed contour needs at least 3 distinct corners, got {0}")]
    TooFewCorners(usize),
    #[error("corner {0} repeats the one before it")]
    RepeatedCorner(usize),
    #[error("sides {0} and {1} are parallel: no corner to offset")]
    Parallel(usize, usize),
    #[error("the cutter radius {0} mm must be a positive number")]
    BadRadius(f64),
}

/// The tool-centre corners for the closed contour `corners` (mm, traversed in order, the last
/// joined to the first) with a cutter of `radius` on `side`.
pub fn cutter_centre_path(
    corners: &[(f64, f64)],
    radius: f64,
    side: CutterSide,
) -> Result<Vec<(f64, f64)>, CutterError> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(CutterError::BadRadius(radius));
    }
    let n = corners.len();
    if n < 3 {
        return Err(CutterError::TooFewCorners(n));
    }
    let sign = match side {
        CutterSide::Left => 1.0,
        CutterSide::Right => -1.0,
    };
    // each side offset: a point on it and its direction
    let mut lines = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (corners[i], corners[(i + 1) % n]);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = dx.hypot(dy);
        if len == 0.0 {
            return Err(CutterError::RepeatedCorner((i + 1) % n));
        }
        let (ux, uy) = (dx / len, dy / len);
        // left normal of the direction (ux, uy) is (−uy, ux)
        let p = (a.0 - sign * radius * uy, a.1 + sign * radius * ux);
        lines.push((p, (ux, uy)));
    }
    // corner i of the centre path: where offset side i−1 meets offset side i
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let j = (i + n - 1) % n;
        let ((p, u), (q, v)) = (lines[j], lines[i]);
        let cross = u.0 * v.1 - u.1 * v.0;
        if cross.abs() < 1e-12 {
            return Err(CutterError::Parallel(j, i));
        }
        // p + s·u = q + t·v
        let s = ((q.0 - p.0) * v.1 - (q.1 - p.1) * v.0) / cross;
        out.push((p.0 + s * u.0, p.1 + s * u.1));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed 004 K4: a 20 mm square pocket, counter-clockwise, a 2 mm cutter inside it (G41: the
    /// tool left of a counter-clockwise wall is inside): the centre runs an 18 mm square.
    #[test]
    fn k4_twenty_mm_pocket_with_a_two_mm_cutter_is_an_eighteen_mm_centre_square() {
        let pocket = [(0.0, 0.0), (20.0, 0.0), (20.0, 20.0), (0.0, 20.0)];
        let centre = cutter_centre_path(&pocket, 1.0, CutterSide::Left).unwrap();
        let want = [(1.0, 1.0), (19.0, 1.0), (19.0, 19.0), (1.0, 19.0)];
        for (c, w) in centre.iter().zip(want) {
            assert!(
                (c.0 - w.0).abs() < 1e-12 && (c.1 - w.1).abs() < 1e-12,
                "{c:?}"
            );
        }
        let side = (centre[1].0 - centre[0].0).hypot(centre[1].1 - centre[0].1);
        assert!((side - 18.0).abs() < 1e-12);
        // G42 on the same contour runs outside: a 22 mm square
        let outside = cutter_centre_path(&pocket, 1.0, CutterSide::Right).unwrap();
        assert!((outside[1].0 - outside[0].0 - 22.0).abs() < 1e-12);
        assert_eq!(
            cutter_centre_path(&pocket[..2], 1.0, CutterSide::Left),
            Err(CutterError::TooFewCorners(2))
        );
        assert!(cutter_centre_path(&pocket, -1.0, CutterSide::Left).is_err());
    }

    #[test]
    fn a_triangle_keeps_its_angles_and_moves_its_sides_by_the_radius() {
        let t = [(0.0, 0.0), (30.0, 0.0), (0.0, 40.0)];
        let c = cutter_centre_path(&t, 2.0, CutterSide::Left).unwrap();
        // every centre corner is the radius from the two sides it joins
        let dist = |p: (f64, f64), a: (f64, f64), b: (f64, f64)| {
            ((b.0 - a.0) * (a.1 - p.1) - (a.0 - p.0) * (b.1 - a.1)).abs()
                / (b.0 - a.0).hypot(b.1 - a.1)
        };
        for i in 0..3 {
            let (prev, next) = ((i + 2) % 3, (i + 1) % 3);
            assert!((dist(c[i], t[prev], t[i]) - 2.0).abs() < 1e-9);
            assert!((dist(c[i], t[i], t[next]) - 2.0).abs() < 1e-9);
        }
    }
}
