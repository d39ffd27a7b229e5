//! Exact area coverage of a pixel that one boundary crosses.
//!
//! Why: an s×s grid of point samples puts the s sample columns of every pixel at the same
//! offsets, so a boundary parallel to the pixel columns (a marker seen square-on) is rendered
//! at one of s + 1 positions per pixel, the same in every row: the edge the image shows is the
//! true one rounded to 1/s px (±0.125 px at s = 4), and it jumps by a whole 1/s px when µm of
//! machine motion carry the true edge across a sample column. A detector measures the rendered
//! edge faithfully, so a 20 mm marker 107 px wide at 150 mm changed its measured depth by
//! ~250 µm in a step between frames that differ by less than a micrometre of motion.
//!
//! Method: the pixel's perimeter is sampled at 4s points; when the reflectance changes exactly
//! twice around it and takes just two values, the two crossings A and B are located by
//! bisection, the boundary's bow off the chord AB by one more bisection along AB's
//! perpendicular bisector, and the pixel's mean is the exact area split by the chord plus the
//! parabolic segment (2/3 · |AB| · bow) — exact for a straight boundary, to third order in the
//! bow for a curved one (a lens-distorted line, a hole's rim). Every one of the s×s interior
//! samples must agree with that split (else, e.g. a marker corner or a thin feature inside the
//! pixel, the caller keeps the s×s mean), so the result is never less faithful than sampling.

/// Bisection steps per crossing: the perimeter interval (1/s px) shrinks to < 1e-4 px.
const BISECTIONS: usize = 14;
/// Largest bow off the chord, relative to the chord, shaded by its parabolic segment.
const MAX_BOW: f64 = 0.05;
/// Interior samples closer than this to the boundary (px) are not used to check the split.
const CHECK_MARGIN_PX: f64 = 1e-3;

/// Mean of `sample` (reflectance, NaN where unseen) over the unit square centred at (cx, cy)
/// when one boundary between two reflectances crosses it, or None (the caller samples the
/// pixel on its s×s grid).
pub(super) fn one_boundary_mean(
    sample: &impl Fn(f64, f64) -> f64,
    cx: f64,
    cy: f64,
    s: usize,
) -> Option<f64> {
    let (x0, y0) = (cx - 0.5, cy - 0.5);
    // Perimeter position t ∈ [0, 4): top edge left → right, right edge down, bottom edge
    // right → left, left edge up (clockwise on screen).
    let at = |t: f64| -> [f64; 2] {
        let side = (t.floor() as i64).rem_euclid(4);
        let f = t - t.floor();
        match side {
            0 => [x0 + f, y0],
            1 => [x0 + 1.0, y0 + f],
            2 => [x0 + 1.0 - f, y0 + 1.0],
            _ => [x0, y0 + 1.0 - f],
        }
    };
    let value = |p: [f64; 2]| sample(p[0], p[1]);
    let n = 4 * s;
    let step = 4.0 / n as f64;
    let ring: Vec<f64> = (0..n).map(|k| value(at(k as f64 * step))).collect();
    if ring.iter().any(|v| v.is_nan()) {
        return None;
    }
    let changes: Vec<usize> = (0..n).filter(|&k| ring[k] != ring[(k + 1) % n]).collect();
    let &[ka, kb] = changes.as_slice() else {
        return None;
    };
    // Reflectance on the arc from A to B (clockwise) and on the rest.
    let (inside, outside) = (ring[ka + 1], ring[ka]);
    if ring[(kb + 1) % n] != outside {
        return None;
    }
    // Crossing in the perimeter interval [k, k + 1]·step, between values `before` and after.
    let crossing = |k: usize| -> f64 {
        let before = ring[k];
        bisect(k as f64 * step, (k + 1) as f64 * step, |t| {
            value(at(t)) == before
        })
    };
    let (ta, tb) = (crossing(ka), crossing(kb));
    let (a, b) = (at(ta), at(tb));
    let chord = [b[0] - a[0], b[1] - a[1]];
    let length = chord[0].hypot(chord[1]);
    if length < 1e-6 {
        return None;
    }
    // Signed distance from the chord, positive on the side of the A → B arc (ta < tb).
    let arc_point = at(0.5 * (ta + tb));
    let cross = |p: [f64; 2]| (chord[0] * (p[1] - a[1]) - chord[1] * (p[0] - a[0])) / length;
    let orientation = cross(arc_point).signum();
    if orientation == 0.0 {
        return None;
    }
    let side = |p: [f64; 2]| orientation * cross(p);
    // Area on the arc's side of the chord: the polygon A, the corners passed, B (shoelace).
    let mut polygon = vec![a];
    let mut corner = ta.floor() + 1.0;
    while corner < tb {
        polygon.push(at(corner));
        corner += 1.0;
    }
    polygon.push(b);
    let twice_area: f64 = (0..polygon.len())
        .map(|k| {
            let (p, q) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum();
    let mut area_inside = 0.5 * twice_area.abs();
    // The boundary's bow off the chord, on AB's perpendicular bisector within the pixel.
    let normal = [
        -chord[1] / length * orientation,
        chord[0] / length * orientation,
    ];
    let middle = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let reach = 0.75; // half the pixel's diagonal bounds every distance within it
    let along = |h: f64| [middle[0] + h * normal[0], middle[1] + h * normal[1]];
    let within = |p: [f64; 2]| p[0] >= x0 && p[0] <= x0 + 1.0 && p[1] >= y0 && p[1] <= y0 + 1.0;
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    // Walk out to the pixel's border on each side of the chord (the bisector leaves it there).
    while within(along(hi + 0.01)) && hi < reach {
        hi += 0.01;
    }
    while within(along(lo - 0.01)) && lo > -reach {
        lo -= 0.01;
    }
    let (v_lo, v_hi) = (value(along(lo)), value(along(hi)));
    if v_lo != outside || v_hi != inside {
        return None;
    }
    // Bow > 0: the boundary lies on the arc's side, so the arc's region is smaller. A bow of
    // more than MAX_BOW of the chord is no gentle curve (a corner inside the pixel, a rim of a
    // few pixels' radius): sampled instead.
    let bow = bisect(lo, hi, |h| value(along(h)) == outside);
    if bow.abs() > MAX_BOW * length {
        return None;
    }
    area_inside -= 2.0 / 3.0 * length * bow;
    if !(0.0..=1.0).contains(&area_inside) {
        return None;
    }
    // Every interior sample must lie on its reflectance's side of the parabola through A, the
    // bow's apex and B.
    let margin = 0.1 * bow.abs() + CHECK_MARGIN_PX;
    for j in 0..s {
        for i in 0..s {
            let p = [
                x0 + (i as f64 + 0.5) / s as f64,
                y0 + (j as f64 + 0.5) / s as f64,
            ];
            let x = 2.0 * ((p[0] - middle[0]) * chord[0] + (p[1] - middle[1]) * chord[1])
                / (length * length);
            let d = side(p) - bow * (1.0 - x * x);
            if d.abs() < margin {
                continue;
            }
            let expected = if d > 0.0 { inside } else { outside };
            if value(p) != expected {
                return None;
            }
        }
    }
    Some(inside * area_inside + outside * (1.0 - area_inside))
}

/// Where `on_lo_side` turns false between `lo` (true) and `hi` (false): the midpoint after
/// [`BISECTIONS`] halvings.
fn bisect(mut lo: f64, mut hi: f64, on_lo_side: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if on_lo_side(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference: the mean of `f` over the pixel centred at the origin, on a 4000 × 4000 grid.
    fn grid_mean(f: &impl Fn(f64, f64) -> f64) -> f64 {
        let m = 4000;
        let mut acc = 0.0;
        for j in 0..m {
            for i in 0..m {
                acc += f(
                    -0.5 + (i as f64 + 0.5) / m as f64,
                    -0.5 + (j as f64 + 0.5) / m as f64,
                );
            }
        }
        acc / (m * m) as f64
    }

    /// A straight boundary at any angle and offset: the exact area of the half-plane's share.
    #[test]
    fn a_straight_boundary_gives_the_exact_area() {
        for (angle, offset) in [
            (0.0f64, 0.13),
            (0.0, -0.37),
            (1e-5, 0.2),
            (0.4, 0.05),
            (1.3, -0.2),
            (-2.2, 0.31),
            (std::f64::consts::FRAC_PI_2, 0.01),
        ] {
            let (c, sn) = (angle.cos(), angle.sin());
            // white (1) where c·x + sn·y > offset, pixel centred at the origin
            let f = |x: f64, y: f64| if c * x + sn * y > offset { 1.0 } else { 0.0 };
            let got = one_boundary_mean(&f, 0.0, 0.0, 4)
                .unwrap_or_else(|| panic!("angle {angle} offset {offset}: no split"));
            let want = grid_mean(&f);
            assert!(
                (got - want).abs() < 2e-4,
                "angle {angle} offset {offset}: {got} vs {want}"
            );
        }
    }

    /// A hole's rim of 5 px radius through the pixel: the parabolic bow brings the area within
    /// 1e-3 of exact.
    #[test]
    fn a_curved_boundary_is_corrected_for_its_bow() {
        let (r, cx) = (5.0, 5.3); // circle of 5 px radius centred 5.3 px to the right
        let f = |x: f64, y: f64| {
            if (x - cx).powi(2) + y * y < r * r {
                0.0
            } else {
                1.0
            }
        };
        let got = one_boundary_mean(&f, 0.0, 0.0, 4).expect("one boundary");
        let want = grid_mean(&f);
        assert!((got - want).abs() < 1e-3, "{got} vs {want}");
    }

    /// A corner inside the pixel is not one boundary: the caller samples it.
    #[test]
    fn a_corner_inside_the_pixel_is_left_to_sampling() {
        let f = |x: f64, y: f64| if x > 0.1 && y > -0.05 { 0.0 } else { 1.0 };
        assert!(one_boundary_mean(&f, 0.0, 0.0, 4).is_none());
        let flat = |_: f64, _: f64| 1.0;
        assert!(one_boundary_mean(&flat, 0.0, 0.0, 4).is_none());
    }
}
