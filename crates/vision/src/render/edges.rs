//! Edge mask of a view: the pixels whose unit square a printed boundary (a change of
//! reflectance on the target) may pass through. Every other pixel sees one reflectance over its
//! whole square, and a row's run of unmarked pixels is a connected strip that no boundary
//! crosses, so it lies in one region of constant reflectance: the renderer samples such a run
//! once and supersamples only the marked pixels.
//!
//! Conservative by construction. Boundaries are the items' outlines plus the internal lines
//! where an item's own pattern changes (a marker's equal neighbouring cells give no line); since
//! an item paints over everything beneath it and a hole inverts both sides of a line, the union
//! over items holds every discontinuity of the target's reflectance. A line is clipped in the
//! camera frame to the frustum of the box that holds the undistorted image (the lens maps target
//! lines to lines in ideal normalised coordinates), then cut into chords of at most
//! [`CHORD_PX`] pixels after distortion; each chord marks every pixel that its bounding box,
//! grown by [`SLACK_PX`], touches. Over half a pixel the distorted curve departs from its chord
//! by ≈ L²κ/8, orders of magnitude below [`SLACK_PX`] for any lens the camera model holds.

use super::{marker_cell, TargetItem};
use crate::camera::CameraModel;
use nalgebra::{Matrix3, Vector3};

/// Longest chord of a traced boundary, pixels.
const CHORD_PX: f64 = 0.5;
/// Margin around each chord's bounding box, pixels.
const SLACK_PX: f64 = 0.05;
/// Most chords one view may trace before the caller falls back to supersampling every pixel.
const MAX_CHORDS: usize = 50_000_000;

/// A reflectance boundary on the target plane (metres, target frame).
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Boundary {
    Segment([f64; 2], [f64; 2]),
    Circle { centre: [f64; 2], radius: f64 },
}

/// Every boundary of `items` (see the module doc). Items were validated by the caller.
pub(super) fn boundaries(items: &[TargetItem]) -> Vec<Boundary> {
    let mut out = Vec::new();
    let rect = |out: &mut Vec<Boundary>, x0: f64, y0: f64, x1: f64, y1: f64| {
        out.push(Boundary::Segment([x0, y0], [x1, y0]));
        out.push(Boundary::Segment([x1, y0], [x1, y1]));
        out.push(Boundary::Segment([x1, y1], [x0, y1]));
        out.push(Boundary::Segment([x0, y1], [x0, y0]));
    };
    for it in items {
        match it {
            TargetItem::Marker {
                dictionary,
                id,
                top_left: [x0, y0],
                side,
                border_bits,
            } => {
                let n = dictionary.marker_size as u32;
                let cells = n + 2 * border_bits;
                let code = dictionary.code(*id).unwrap_or(0);
                let at = |k: u32| k as f64 * side / cells as f64;
                rect(&mut out, *x0, *y0, x0 + side, y0 + side);
                let cell = |r: u32, c: u32| marker_cell(code, n, *border_bits, r, c);
                // Internal lines, merged along runs of differing neighbours.
                for k in 1..cells {
                    let mut run: Option<u32> = None;
                    for r in 0..=cells {
                        let differs = r < cells && cell(r, k - 1) != cell(r, k);
                        match (differs, run) {
                            (true, None) => run = Some(r),
                            (false, Some(r0)) => {
                                out.push(Boundary::Segment(
                                    [x0 + at(k), y0 + at(r0)],
                                    [x0 + at(k), y0 + at(r)],
                                ));
                                run = None;
                            }
                            _ => {}
                        }
                    }
                    let mut run: Option<u32> = None;
                    for c in 0..=cells {
                        let differs = c < cells && cell(k - 1, c) != cell(k, c);
                        match (differs, run) {
                            (true, None) => run = Some(c),
                            (false, Some(c0)) => {
                                out.push(Boundary::Segment(
                                    [x0 + at(c0), y0 + at(k)],
                                    [x0 + at(c), y0 + at(k)],
                                ));
                                run = None;
                            }
                            _ => {}
                        }
                    }
                }
            }
            TargetItem::Checkerboard {
                top_left: [x0, y0],
                square,
                squares_x,
                squares_y,
                ..
            } => {
                let (x1, y1) = (
                    x0 + *squares_x as f64 * square,
                    y0 + *squares_y as f64 * square,
                );
                for k in 0..=*squares_x {
                    let x = x0 + k as f64 * square;
                    out.push(Boundary::Segment([x, *y0], [x, y1]));
                }
                for k in 0..=*squares_y {
                    let y = y0 + k as f64 * square;
                    out.push(Boundary::Segment([*x0, y], [x1, y]));
                }
            }
            TargetItem::Hole { centre, diameter }
            | TargetItem::Disc {
                centre, diameter, ..
            } => out.push(Boundary::Circle {
                centre: *centre,
                radius: diameter / 2.0,
            }),
            TargetItem::Rectangle { top_left, size, .. } => rect(
                &mut out,
                top_left[0],
                top_left[1],
                top_left[0] + size[0],
                top_left[1] + size[1],
            ),
        }
    }
    out
}

/// Marks pixels of a `w`×`h` mask (row-major, 1 = an edge may cross the pixel).
pub(super) struct EdgeTracer<'a> {
    camera: &'a CameraModel,
    /// Target → camera rotation and translation.
    rot: Matrix3<f64>,
    trans: Vector3<f64>,
    /// Ideal normalised box [x_min, x_max, y_min, y_max] holding the whole image.
    bbox: [f64; 4],
    w: usize,
    h: usize,
    pub mask: Vec<u8>,
    chords: usize,
}

impl<'a> EdgeTracer<'a> {
    /// `buffer`: storage for the mask (any content; reused to spare fresh pages).
    pub fn new(
        camera: &'a CameraModel,
        rot: Matrix3<f64>,
        trans: Vector3<f64>,
        bbox: [f64; 4],
        mut buffer: Vec<u8>,
    ) -> Self {
        let (w, h) = (camera.width as usize, camera.height as usize);
        buffer.clear();
        buffer.resize(w * h, 0);
        EdgeTracer {
            camera,
            rot,
            trans,
            bbox,
            w,
            h,
            mask: buffer,
            chords: 0,
        }
    }

    fn to_camera(&self, p: [f64; 2]) -> Vector3<f64> {
        self.rot * Vector3::new(p[0], p[1], 0.0) + self.trans
    }

    /// Pixel of a camera-frame point in front of the camera.
    fn pixel(&self, p: &Vector3<f64>) -> [f64; 2] {
        let (xd, yd) = self.camera.distortion.distort(p.x / p.z, p.y / p.z);
        self.camera.normalized_to_pixel(xd, yd)
    }

    /// Trace one boundary; false when the tracing cannot be trusted (a hole's rim crosses the
    /// camera plane, a non-finite projection, or the chord budget ran out).
    pub fn trace(&mut self, b: &Boundary) -> bool {
        match b {
            Boundary::Segment(a, b) => {
                let (pa, pb) = (self.to_camera(*a), self.to_camera(*b));
                let d = pb - pa;
                // Liang–Barsky against the frustum x ≥ x_min·z, x ≤ x_max·z, y ≥ y_min·z,
                // y ≤ y_max·z, z ≥ 1e-12 m: each is f(t) = f0 + t·df ≥ 0, linear in t.
                let [x0, x1, y0, y1] = self.bbox;
                let planes = [
                    (pa.x - x0 * pa.z, d.x - x0 * d.z),
                    (x1 * pa.z - pa.x, x1 * d.z - d.x),
                    (pa.y - y0 * pa.z, d.y - y0 * d.z),
                    (y1 * pa.z - pa.y, y1 * d.z - d.y),
                    (pa.z - 1e-12, d.z),
                ];
                let (mut t0, mut t1) = (0.0f64, 1.0f64);
                for (f0, df) in planes {
                    if df == 0.0 {
                        if f0 < 0.0 {
                            return true;
                        }
                    } else {
                        let t = -f0 / df;
                        if df > 0.0 {
                            t0 = t0.max(t);
                        } else {
                            t1 = t1.min(t);
                        }
                    }
                }
                if !(t0 <= t1) {
                    return true;
                }
                self.trace_curve(t0, t1, |t| pa + d * t)
            }
            Boundary::Circle { centre, radius } => {
                let c = self.to_camera(*centre);
                let (a, bz) = (self.rot[(2, 0)] * radius, self.rot[(2, 1)] * radius);
                if !(c.z - (a * a + bz * bz).sqrt() > 1e-12) {
                    return false;
                }
                let (rot, r) = (self.rot, *radius);
                self.trace_curve(0.0, std::f64::consts::TAU, move |t| {
                    c + rot * Vector3::new(r * t.cos(), r * t.sin(), 0.0)
                })
            }
        }
    }

    /// Cut the curve `point(t)`, t ∈ [t0, t1] (camera frame, z > 0), into chords ≤ CHORD_PX
    /// and mark them.
    fn trace_curve(&mut self, t0: f64, t1: f64, point: impl Fn(f64) -> Vector3<f64>) -> bool {
        const START_PIECES: usize = 8;
        let mut stack = Vec::with_capacity(64);
        let tk = |k: usize| t0 + (t1 - t0) * k as f64 / START_PIECES as f64;
        for k in (0..START_PIECES).rev() {
            let (ta, tb) = (tk(k), tk(k + 1));
            stack.push((ta, self.pixel(&point(ta)), tb, self.pixel(&point(tb))));
        }
        while let Some((ta, pa, tb, pb)) = stack.pop() {
            if !(pa.iter().chain(&pb).all(|v| v.is_finite())) {
                return false;
            }
            let long = (pa[0] - pb[0]).hypot(pa[1] - pb[1]) > CHORD_PX;
            let tm = 0.5 * (ta + tb);
            if long && tm > ta && tm < tb {
                let pm = self.pixel(&point(tm));
                stack.push((tm, pm, tb, pb));
                stack.push((ta, pa, tm, pm));
            } else {
                self.chords += 1;
                if self.chords > MAX_CHORDS {
                    return false;
                }
                self.mark_chord(pa, pb);
            }
        }
        true
    }

    /// Mark the pixels whose unit square meets the chord's bounding box grown by SLACK_PX.
    fn mark_chord(&mut self, a: [f64; 2], b: [f64; 2]) {
        let (w, h) = (self.w as f64, self.h as f64);
        let lo = [a[0].min(b[0]) - SLACK_PX, a[1].min(b[1]) - SLACK_PX];
        let hi = [a[0].max(b[0]) + SLACK_PX, a[1].max(b[1]) + SLACK_PX];
        if hi[0] < -0.5 || hi[1] < -0.5 || lo[0] > w - 0.5 || lo[1] > h - 0.5 {
            return;
        }
        // Pixel k covers [k − 0.5, k + 0.5].
        let first = |v: f64| (v + 0.5).floor().max(0.0) as usize;
        let last = |v: f64, n: f64| (v + 0.5).floor().min(n - 1.0) as usize;
        let (i0, i1, j0, j1) = (first(lo[0]), last(hi[0], w), first(lo[1]), last(hi[1], h));
        for j in j0..=j1 {
            self.mask[j * self.w + i0..=j * self.w + i1].fill(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aruco::Dictionary;
    use crate::camera::Distortion;

    #[test]
    fn marker_boundaries_are_the_outline_and_the_bit_changes_only() {
        let dictionary = Dictionary::predefined("DICT_4X4_50").unwrap();
        let item = TargetItem::Marker {
            dictionary,
            id: 0,
            top_left: [0.0, 0.0],
            side: 6.0,
            border_bits: 1,
        };
        let b = boundaries(std::slice::from_ref(&item));
        // Every boundary segment separates different reflectances along its whole length,
        // except the outline (paper on the outside).
        let refl = |x: f64, y: f64| item.reflectance(x, y).unwrap_or(1.0);
        let mut internal = 0;
        for s in &b[4..] {
            let Boundary::Segment(p, q) = s else {
                panic!("{s:?}")
            };
            internal += 1;
            let vertical = p[0] == q[0];
            let (lo, hi) = if vertical {
                (p[1].min(q[1]), p[1].max(q[1]))
            } else {
                (p[0].min(q[0]), p[0].max(q[0]))
            };
            let mut t = lo + 0.5;
            while t < hi {
                let (l, r) = if vertical {
                    (refl(p[0] - 0.5, t), refl(p[0] + 0.5, t))
                } else {
                    (refl(t, p[1] - 0.5), refl(t, p[1] + 0.5))
                };
                assert_ne!(l, r, "{s:?} at {t}");
                t += 1.0;
            }
        }
        assert!(internal > 4, "a 4×4 code has internal edges: {internal}");
        // And every cell-to-cell change lies on some boundary.
        let on = |x: f64, y: f64| {
            b.iter().any(|s| match s {
                Boundary::Segment(p, q) => {
                    (p[0] == q[0] && p[0] == x && y > p[1].min(q[1]) && y < p[1].max(q[1]))
                        || (p[1] == q[1] && p[1] == y && x > p[0].min(q[0]) && x < p[0].max(q[0]))
                }
                _ => false,
            })
        };
        for r in 0..6 {
            for k in 1..6 {
                let (y, x) = (r as f64 + 0.5, k as f64);
                if refl(x - 0.5, y) != refl(x + 0.5, y) {
                    assert!(on(x, y), "vertical change at ({x}, {y})");
                }
                if refl(y, x - 0.5) != refl(y, x + 0.5) {
                    assert!(on(y, x), "horizontal change at ({y}, {x})");
                }
            }
        }
    }

    #[test]
    fn a_traced_line_marks_a_thin_band_that_covers_it() {
        let cam = CameraModel::new(
            200,
            100,
            100.0,
            100.0,
            99.5,
            49.5,
            Distortion::BrownConrady([-0.2, 0.05, 0.001, -0.001, 0.0]),
        )
        .unwrap();
        let mut t = EdgeTracer::new(
            &cam,
            Matrix3::identity(),
            Vector3::new(0.0, 0.0, 1.0),
            [-2.0, 2.0, -1.0, 1.0],
            Vec::new(),
        );
        let (a, b) = ([-0.7, -0.3], [0.8, 0.35]);
        assert!(t.trace(&Boundary::Segment(a, b)));
        // Every point of the projected line lies in a marked pixel.
        for k in 0..=10_000 {
            let s = k as f64 / 10_000.0;
            let p = Vector3::new(a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), 1.0);
            let [u, v] = t.pixel(&p);
            let (i, j) = ((u + 0.5).floor() as usize, (v + 0.5).floor() as usize);
            assert_eq!(t.mask[j * 200 + i], 1, "({u}, {v})");
        }
        // The band is thin: about 2 pixels per unit of length, not a blob.
        let marked = t.mask.iter().filter(|&&m| m == 1).count();
        let len = {
            let ([u0, v0], [u1, v1]) = (
                t.pixel(&Vector3::new(a[0], a[1], 1.0)),
                t.pixel(&Vector3::new(b[0], b[1], 1.0)),
            );
            (u1 - u0).hypot(v1 - v0)
        };
        assert!(
            (marked as f64) < 3.0 * len,
            "{marked} pixels for a {len} px line"
        );
    }
}
