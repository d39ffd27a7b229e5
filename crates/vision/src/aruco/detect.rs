//! ArUco marker detection: adaptive threshold → outer contours → convex quads → perspective
//! sampling of the cell grid → Otsu bits → dictionary lookup with rotation and error correction →
//! sub-pixel corners from step-edge fits of the four outer sides (see `edge_fit`).
//!
//! Output corners follow OpenCV: top-left, top-right, bottom-right, bottom-left of the printed
//! marker, clockwise on screen, in the crate's pixel convention.

use super::dictionary::Dictionary;
use crate::contour::outer_contours;
use crate::edge_fit::{fit_step_edge, intersect, EdgeWindow};
use crate::error::{invalid, Result, VisionError};
use crate::polygon::{approx_closed, is_convex};
use crate::threshold::adaptive_threshold_mean_into;
use image::GrayImage;
use metrocell_camera_model::homography::{apply, homography_dlt};
use nalgebra::{Matrix2, Point2};

/// Detector settings; defaults mirror OpenCV's `DetectorParameters` where a counterpart exists.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectorParams {
    /// Odd adaptive-threshold window sizes, px (OpenCV: 3, 13, 23).
    pub threshold_windows: Vec<u32>,
    /// Adaptive threshold constant C, grey levels (OpenCV 7).
    pub threshold_constant: f64,
    /// Contour length limits relative to the larger image side (OpenCV 0.03 and 4.0).
    pub min_perimeter_rate: f64,
    pub max_perimeter_rate: f64,
    /// Douglas–Peucker tolerance relative to the contour length (OpenCV 0.03).
    pub polygonal_approx_accuracy_rate: f64,
    /// Minimum quad side relative to the contour length (OpenCV 0.05).
    pub min_corner_distance_rate: f64,
    /// Minimum distance of quad corners from the image border, px (OpenCV 3).
    pub min_distance_to_border: f64,
    /// Fraction of the dictionary's correction capacity used (OpenCV 0.6).
    pub error_correction_rate: f64,
    /// White border cells tolerated, relative to n² (OpenCV 0.35).
    pub max_erroneous_bits_in_border_rate: f64,
    /// Minimum grey-level standard deviation inside a candidate (OpenCV 5).
    pub min_otsu_std_dev: f64,
    /// Cell margin ignored when sampling bits (OpenCV 0.13).
    pub cell_margin: f64,
    /// Refine corners by step-edge fits (otherwise: contour polygon corners).
    pub refine_corners: bool,
    /// Worker threads for the threshold windows and the corner fits; 0 = all available cores.
    /// Results do not depend on it.
    pub threads: usize,
}

impl Default for DetectorParams {
    fn default() -> Self {
        Self {
            threshold_windows: vec![3, 13, 23],
            threshold_constant: 7.0,
            min_perimeter_rate: 0.03,
            max_perimeter_rate: 4.0,
            polygonal_approx_accuracy_rate: 0.03,
            min_corner_distance_rate: 0.05,
            min_distance_to_border: 3.0,
            error_correction_rate: 0.6,
            max_erroneous_bits_in_border_rate: 0.35,
            min_otsu_std_dev: 5.0,
            cell_margin: 0.13,
            refine_corners: true,
            threads: 0,
        }
    }
}

/// One detected marker.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectedMarker {
    pub id: usize,
    /// Top-left, top-right, bottom-right, bottom-left (px).
    pub corners: [Point2<f64>; 4],
    /// Covariance of each corner (px²), from the edge fits' residuals; NaN-filled when the
    /// corner could not be refined. It is the noise (statistical) part only: on noise-free
    /// renders a model floor of about 0.01–0.02 px remains (lens distortion beyond the fitted
    /// parabola, 8-bit quantisation) that the covariance does not include.
    pub corner_covariance: [Matrix2<f64>; 4],
    /// Bits corrected by the dictionary lookup.
    pub bit_errors: u32,
}

/// Detect markers of `dict` in `img`.
pub fn detect_markers(
    img: &GrayImage,
    dict: &Dictionary,
    params: &DetectorParams,
) -> Result<Vec<DetectedMarker>> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w < 16 || h < 16 {
        return Err(VisionError::ImageTooSmall {
            what: "detect_markers input",
            width: img.width(),
            height: img.height(),
        });
    }
    for &win in &params.threshold_windows {
        if win < 3 || win % 2 == 0 {
            return Err(invalid(
                "threshold_windows",
                format!("window {win} must be odd and ≥ 3"),
            ));
        }
    }
    if params.threshold_windows.is_empty() {
        return Err(invalid("threshold_windows", "needs at least one window"));
    }
    let max_side = w.max(h) as f64;
    let min_perim = (params.min_perimeter_rate * max_side).max(12.0);
    let max_perim = params.max_perimeter_rate * max_side;
    let max_bit_errors = (dict.max_correction_bits as f64 * params.error_correction_rate) as u32;
    let threads = match params.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };

    // Stage 1: candidate quads per threshold window (independent, so in parallel).
    let window_quads = |win: u32| -> Vec<[[f64; 2]; 4]> {
        let mut mask = Vec::new();
        adaptive_threshold_mean_into(img, win, params.threshold_constant, &mut mask);
        let contours = outer_contours(
            &mut mask,
            w,
            h,
            (min_perim / 4.0) as usize,
            max_perim as usize,
        );
        contours
            .iter()
            .filter(|c| (min_perim..=max_perim).contains(&(c.points.len() as f64)))
            .filter_map(|c| quad_from_contour(&c.points, c.points.len() as f64, w, h, params))
            .collect()
    };
    let per_window: Vec<Vec<[[f64; 2]; 4]>> = if threads > 1 && params.threshold_windows.len() > 1 {
        std::thread::scope(|s| {
            let handles: Vec<_> = params
                .threshold_windows
                .iter()
                .map(|&win| s.spawn(move || window_quads(win)))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("threshold worker panicked"))
                .collect()
        })
    } else {
        params
            .threshold_windows
            .iter()
            .map(|&win| window_quads(win))
            .collect()
    };

    // Stage 2: decode in window order; the first decoding of a marker wins.
    let mut decoded: Vec<(usize, [[f64; 2]; 4], u32)> = Vec::new();
    for quad in per_window.iter().flatten() {
        if decoded
            .iter()
            .any(|(_, q, _)| point_in_quad(q, centroid(quad)))
        {
            continue;
        }
        let Some((id, rotation, bit_errors)) = decode(img, quad, dict, params, max_bit_errors)
        else {
            continue;
        };
        let rough: [[f64; 2]; 4] = std::array::from_fn(|k| quad[(k + rotation) % 4]);
        // A larger quad containing an earlier one (outer vs inner contour) replaces it.
        decoded.retain(|(_, q, _)| !point_in_quad(&rough, centroid(q)));
        decoded.push((id, rough, bit_errors));
    }

    // Stage 3: sub-pixel corners (independent per marker, so in parallel).
    let finish = |(id, rough, bit_errors): &(usize, [[f64; 2]; 4], u32)| -> DetectedMarker {
        let (corners, corner_covariance) = if params.refine_corners {
            refine(img, rough, dict.marker_size + 2)
        } else {
            (
                rough.map(|p| Point2::new(p[0], p[1])),
                [Matrix2::from_element(f64::NAN); 4],
            )
        };
        DetectedMarker {
            id: *id,
            corners,
            corner_covariance,
            bit_errors: *bit_errors,
        }
    };
    if threads > 1 && decoded.len() > 1 {
        let chunk = decoded.len().div_ceil(threads);
        Ok(std::thread::scope(|s| {
            let handles: Vec<_> = decoded
                .chunks(chunk)
                .map(|c| s.spawn(move || c.iter().map(finish).collect::<Vec<_>>()))
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().expect("refinement worker panicked"))
                .collect()
        }))
    } else {
        Ok(decoded.iter().map(finish).collect())
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn centroid(q: &[[f64; 2]; 4]) -> [f64; 2] {
    [
        (q[0][0] + q[1][0] + q[2][0] + q[3][0]) / 4.0,
        (q[0][1] + q[1][1] + q[2][1] + q[3][1]) / 4.0,
    ]
}

fn point_in_quad<P: Copy + Into<[f64; 2]>>(q: &[P; 4], p: [f64; 2]) -> bool {
    let q: [[f64; 2]; 4] = q.map(|v| v.into());
    (0..4).all(|k| {
        let (a, b) = (q[k], q[(k + 1) % 4]);
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0.0
    })
}

/// Four-vertex convex polygon from a contour, clockwise on screen, or None.
fn quad_from_contour(
    pts: &[(i32, i32)],
    len: f64,
    w: usize,
    h: usize,
    params: &DetectorParams,
) -> Option<[[f64; 2]; 4]> {
    let idx = approx_closed(pts, params.polygonal_approx_accuracy_rate * len);
    if idx.len() != 4 {
        return None;
    }
    let mut q: [[f64; 2]; 4] =
        std::array::from_fn(|k| [pts[idx[k]].0 as f64, pts[idx[k]].1 as f64]);
    if !is_convex(&q) {
        return None;
    }
    let min_side = params.min_corner_distance_rate * len;
    if (0..4).any(|k| dist(q[k], q[(k + 1) % 4]) < min_side) {
        return None;
    }
    let b = params.min_distance_to_border;
    if q.iter()
        .any(|p| p[0] < b || p[1] < b || p[0] > w as f64 - 1.0 - b || p[1] > h as f64 - 1.0 - b)
    {
        return None;
    }
    // Clockwise on screen (y down) means a positive cross product of consecutive edges.
    let cross =
        (q[1][0] - q[0][0]) * (q[2][1] - q[1][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[1][0]);
    if cross < 0.0 {
        q.swap(1, 3);
    }
    Some(q)
}

/// Bilinear interpolation (pixel centres at integers, clamped at the border).
fn bilinear(img: &GrayImage, x: f64, y: f64) -> f64 {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let x = x.clamp(0.0, (w - 1) as f64);
    let y = y.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (x.floor() as i64, y.floor() as i64);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let g = |xx: i64, yy: i64| img.get_pixel(xx as u32, yy as u32)[0] as f64;
    (g(x0, y0) * (1.0 - fx) + g(x1, y0) * fx) * (1.0 - fy)
        + (g(x0, y1) * (1.0 - fx) + g(x1, y1) * fx) * fy
}

/// Otsu threshold of a sample set (grey levels 0–255).
fn otsu(values: &[f64]) -> f64 {
    let mut hist = [0f64; 256];
    for &v in values {
        hist[v.round().clamp(0.0, 255.0) as usize] += 1.0;
    }
    let total = values.len() as f64;
    let sum_all: f64 = hist.iter().enumerate().map(|(i, c)| i as f64 * c).sum();
    let (mut w0, mut sum0, mut best, mut thr) = (0.0, 0.0, -1.0, 127.0);
    for (t, &c) in hist.iter().enumerate() {
        w0 += c;
        sum0 += t as f64 * c;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0, (sum_all - sum0) / w1);
        let between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            thr = t as f64;
        }
    }
    thr
}

/// Sample the cell grid and identify the marker: (id, rotation, bit errors).
fn decode(
    img: &GrayImage,
    quad: &[[f64; 2]; 4],
    dict: &Dictionary,
    params: &DetectorParams,
    max_bit_errors: u32,
) -> Option<(usize, usize, u32)> {
    let n = dict.marker_size;
    let cells = n + 2;
    let cf = cells as f64;
    let hmg = homography_dlt(&[[0.0, 0.0], [cf, 0.0], [cf, cf], [0.0, cf]], quad).ok()?;
    const K: usize = 4; // samples per cell axis
    let mut samples = Vec::with_capacity(cells * cells * K * K);
    for r in 0..cells {
        for c in 0..cells {
            for j in 0..K {
                for i in 0..K {
                    let m = params.cell_margin;
                    let u = c as f64 + m + (i as f64 + 0.5) / K as f64 * (1.0 - 2.0 * m);
                    let v = r as f64 + m + (j as f64 + 0.5) / K as f64 * (1.0 - 2.0 * m);
                    let p = apply(&hmg, [u, v])?;
                    samples.push(bilinear(img, p[0], p[1]));
                }
            }
        }
    }
    let mean = samples.iter().sum::<f64>() / samples.len() as f64;
    let var = samples.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / samples.len() as f64;
    if var.sqrt() < params.min_otsu_std_dev {
        return None;
    }
    let thr = otsu(&samples);
    let white = |r: usize, c: usize| {
        let s = &samples[(r * cells + c) * K * K..(r * cells + c + 1) * K * K];
        s.iter().filter(|&&v| v > thr).count() * 2 > K * K
    };
    let mut border_errors = 0usize;
    for k in 0..cells {
        border_errors += white(0, k) as usize + white(cells - 1, k) as usize;
        if k > 0 && k < cells - 1 {
            border_errors += white(k, 0) as usize + white(k, cells - 1) as usize;
        }
    }
    if border_errors as f64 > params.max_erroneous_bits_in_border_rate * (n * n) as f64 {
        return None;
    }
    let mut code = 0u64;
    for r in 1..=n {
        for c in 1..=n {
            code = (code << 1) | white(r, c) as u64;
        }
    }
    let ident = dict.identify(code, max_bit_errors)?;
    Some((ident.id, ident.rotation, ident.bit_errors))
}

/// Fit the four outer sides and intersect adjacent ones. Falls back to the rough corner (with a
/// NaN covariance) for corners whose sides could not be fitted.
fn refine(
    img: &GrayImage,
    q: &[[f64; 2]; 4],
    cells: usize,
) -> ([Point2<f64>; 4], [Matrix2<f64>; 4]) {
    let sides: Vec<f64> = (0..4).map(|k| dist(q[k], q[(k + 1) % 4])).collect();
    let cell_px = sides.iter().cloned().fold(f64::INFINITY, f64::min) / cells as f64;
    let band = (0.45 * cell_px).clamp(1.2, 4.0);
    let lines: Vec<_> = (0..4)
        .map(|k| {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            let len = sides[k];
            // Outward normal of a clockwise (on screen) polygon side: (t.y, −t.x); outside is white.
            let t = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
            let trim = ((band + 2.0) / len).clamp(0.08, 0.3);
            fit_step_edge(
                img,
                &EdgeWindow {
                    p0: a,
                    p1: b,
                    bright_normal: [t[1], -t[0]],
                    band,
                    trim,
                },
            )
        })
        .collect();
    let mut corners = q.map(|p| Point2::new(p[0], p[1]));
    let mut covs = [Matrix2::from_element(f64::NAN); 4];
    for k in 0..4 {
        let prev = (k + 3) % 4;
        if let (Some(l1), Some(l2)) = (&lines[prev], &lines[k]) {
            if let Some((p, c)) = intersect(l1, l2) {
                // Guard against a diverged fit: the refined corner must stay near the rough one.
                if (p - corners[k]).norm() < 0.5 * cell_px + 2.0 {
                    corners[k] = p;
                    covs[k] = c;
                }
            }
        }
    }
    (corners, covs)
}
