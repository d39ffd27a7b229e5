//! G2/G3 arcs (and helices) as chords no farther than a tolerance from the true arc.
//!
//! Plane conventions (RS274/NGC): G17 arcs in X–Y (normal Z, centre offsets I J), G18 in Z–X
//! (normal Y, offsets K I), G19 in Y–Z (normal X, offsets J K). G2 turns clockwise and G3
//! counter-clockwise seen from the positive end of the normal axis. With `R`, a positive radius
//! takes the shorter arc and a negative one the longer; R cannot describe a full circle.

use nalgebra::{Vector2, Vector3};
use std::f64::consts::PI;

/// The arc's plane as axis indices (first, second, normal) into X Y Z.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArcPlane(pub [usize; 3]);

impl ArcPlane {
    pub const XY: ArcPlane = ArcPlane([0, 1, 2]);
    pub const ZX: ArcPlane = ArcPlane([2, 0, 1]);
    pub const YZ: ArcPlane = ArcPlane([1, 2, 0]);
}

/// How the program gives the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArcCentre {
    /// I J K: centre − start, per machine axis.
    Offset(Vector3<f64>),
    /// R: signed radius.
    Radius(f64),
}

/// The most chords one arc may take. An arc's chord count grows as √(radius / tolerance): a
/// 10 m radius at 1 µm is ~7000, so a count beyond this is a centre offset or radius no machine
/// has (an I of 10⁹ in a program asked for 2 million chords and 100 MiB, found by fuzzing).
pub const MAX_ARC_CHORDS: usize = 100_000;

/// Points along the arc from `start` to `end` (both in program units), the start excluded and
/// the end included exactly, spaced so each chord stays within `chord_tolerance` of the arc.
/// `radius_tolerance` is how far start and end may disagree on the radius (program units). An
/// arc that would take more than [`MAX_ARC_CHORDS`] is an error.
pub fn arc_points(
    start: &Vector3<f64>,
    end: &Vector3<f64>,
    centre: ArcCentre,
    clockwise: bool,
    plane: ArcPlane,
    chord_tolerance: f64,
    radius_tolerance: f64,
) -> Result<Vec<Vector3<f64>>, String> {
    let [a, b, n] = plane.0;
    let s = Vector2::new(start[a], start[b]);
    let e = Vector2::new(end[a], end[b]);
    let c = match centre {
        ArcCentre::Offset(o) => s + Vector2::new(o[a], o[b]),
        ArcCentre::Radius(r) => {
            let d = (e - s).norm();
            if d == 0.0 {
                return Err("an arc given by R must not end where it starts (R cannot describe a full circle; use I J K)".into());
            }
            if d > 2.0 * r.abs() + radius_tolerance {
                return Err(format!("R = {r} is too small for an arc of chord {d}"));
            }
            let h = (r * r - d * d / 4.0).max(0.0).sqrt();
            let u = (e - s) / d;
            let left = Vector2::new(-u.y, u.x);
            let side = if clockwise == (r < 0.0) { 1.0 } else { -1.0 };
            (s + e) / 2.0 + left * (side * h)
        }
    };
    let r_start = (s - c).norm();
    let r_end = (e - c).norm();
    if r_start == 0.0 {
        return Err("the arc's centre is its start point".into());
    }
    if (r_start - r_end).abs() > radius_tolerance {
        return Err(format!(
            "the arc's end is not on its circle: radius {r_start} at the start, {r_end} at the end"
        ));
    }
    let angle = |p: Vector2<f64>| (p.y - c.y).atan2(p.x - c.x);
    let (ts, te) = (angle(s), angle(e));
    let full_circle =
        (e - s).norm() < radius_tolerance * 1e-3 && matches!(centre, ArcCentre::Offset(_));
    let ccw_sweep = |from: f64, to: f64| {
        let mut d = (to - from).rem_euclid(2.0 * PI);
        if d == 0.0 && full_circle {
            d = 2.0 * PI;
        }
        d
    };
    let sweep = if clockwise {
        -ccw_sweep(te, ts)
    } else {
        ccw_sweep(ts, te)
    };
    let max_step = if chord_tolerance < r_start {
        2.0 * (1.0 - chord_tolerance / r_start).acos()
    } else {
        PI / 2.0
    };
    let chords = (sweep.abs() / max_step).ceil();
    if !(chords <= MAX_ARC_CHORDS as f64) {
        return Err(format!(
            "an arc of radius {r_start} would take {chords:.0} chords of tolerance {chord_tolerance} (more than {MAX_ARC_CHORDS}): is its centre offset (I J K) or radius (R) in the program's units?"
        ));
    }
    let count = (chords as usize).max(1);
    let mut points = Vec::with_capacity(count);
    for k in 1..count {
        let f = k as f64 / count as f64;
        let t = ts + sweep * f;
        let mut p = *start;
        p[a] = c.x + r_start * t.cos();
        p[b] = c.y + r_start * t.sin();
        p[n] = start[n] + (end[n] - start[n]) * f;
        points.push(p);
    }
    points.push(*end);
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_sagitta(
        start: Vector3<f64>,
        points: &[Vector3<f64>],
        centre: Vector2<f64>,
        r: f64,
    ) -> f64 {
        let mut prev = start;
        let mut worst: f64 = 0.0;
        for p in points {
            let mid = Vector2::new((prev.x + p.x) / 2.0, (prev.y + p.y) / 2.0);
            worst = worst.max(r - (mid - centre).norm());
            prev = *p;
        }
        worst
    }

    #[test]
    fn quarter_circle_clockwise_within_tolerance() {
        // G17 G2 from (10, 0) to (0, -10) around the origin: a clockwise quarter
        let (s, e) = (Vector3::new(10.0, 0.0, 0.0), Vector3::new(0.0, -10.0, 0.0));
        let pts = arc_points(
            &s,
            &e,
            ArcCentre::Offset(Vector3::new(-10.0, 0.0, 0.0)),
            true,
            ArcPlane::XY,
            0.001,
            1e-4,
        )
        .unwrap();
        assert_eq!(*pts.last().unwrap(), e);
        assert!(
            pts.iter().all(|p| p.x >= -1e-12 && p.y <= 1e-12),
            "stays in the fourth quadrant"
        );
        let sag = max_sagitta(s, &pts, Vector2::zeros(), 10.0);
        assert!(sag <= 0.001 + 1e-12 && sag > 0.0005, "sagitta {sag}");
        // the same arc with R takes the same centre
        let by_r = arc_points(
            &s,
            &e,
            ArcCentre::Radius(10.0),
            true,
            ArcPlane::XY,
            0.001,
            1e-4,
        )
        .unwrap();
        assert_eq!(pts.len(), by_r.len());
        assert!(pts.iter().zip(&by_r).all(|(p, q)| (p - q).norm() < 1e-9));
    }

    #[test]
    fn full_circle_and_helix() {
        let s = Vector3::new(5.0, 0.0, 0.0);
        let e = Vector3::new(5.0, 0.0, -2.0);
        let pts = arc_points(
            &s,
            &e,
            ArcCentre::Offset(Vector3::new(-5.0, 0.0, 0.0)),
            false,
            ArcPlane::XY,
            0.01,
            1e-4,
        )
        .unwrap();
        assert!(pts.len() > 10);
        // halfway round the circle, halfway down
        let mid = pts[pts.len() / 2 - 1];
        assert!((mid.z + 1.0).abs() < 0.2 && mid.x < -4.0, "{mid:?}");
    }

    /// Found by fuzzing (tests/fuzz `gcode_programs`): a full circle with a centre offset of 10⁹
    /// asked for 2 million chords (100 MiB); 10¹² for 3.2 GiB.
    #[test]
    fn an_arc_no_machine_has_is_an_error_not_an_allocation() {
        for i in [1e9, 1e12, 1e28] {
            let start = Vector3::new(0.0, 0.0, 9.0);
            let e = arc_points(
                &start,
                &start,
                ArcCentre::Offset(Vector3::new(i, 0.0, 0.0)),
                true,
                ArcPlane::XY,
                1e-3,
                1e-3,
            )
            .unwrap_err();
            assert!(e.contains("chords") && e.contains("I J K"), "{e}");
        }
        // a 10 m circle at 1 µm is fine
        let start = Vector3::zeros();
        let p = arc_points(
            &start,
            &start,
            ArcCentre::Offset(Vector3::new(10_000.0, 0.0, 0.0)),
            false,
            ArcPlane::XY,
            1e-3,
            1e-3,
        )
        .unwrap();
        assert!(p.len() > 1000 && p.len() < MAX_ARC_CHORDS, "{}", p.len());
    }

    #[test]
    fn bad_arcs_are_errors() {
        let s = Vector3::new(10.0, 0.0, 0.0);
        assert!(arc_points(
            &s,
            &Vector3::new(0.0, 12.0, 0.0),
            ArcCentre::Offset(Vector3::new(-10.0, 0.0, 0.0)),
            false,
            ArcPlane::XY,
            0.001,
            1e-3
        )
        .unwrap_err()
        .contains("not on its circle"));
        assert!(arc_points(
            &s,
            &s,
            ArcCentre::Radius(5.0),
            false,
            ArcPlane::XY,
            0.001,
            1e-3
        )
        .is_err());
        assert!(arc_points(
            &s,
            &Vector3::new(-10.0, 0.0, 0.0),
            ArcCentre::Radius(2.0),
            false,
            ArcPlane::XY,
            0.001,
            1e-3
        )
        .unwrap_err()
        .contains("too small"));
    }
}
