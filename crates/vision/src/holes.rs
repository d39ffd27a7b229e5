//! Drilled holes / circular blobs at predicted positions (seed 000: a 6×6 grid of holes drilled
//! through a checkerboard over an inverse-contrast backing, so each hole shows the opposite
//! colour of its square). Each nominal cell is searched in a window around its predicted pixel
//! position, which is the assignment of holes to nominal grid cells; a cell with no acceptable
//! blob is rejected with a reason, never silently matched to a neighbour.
//!
//! Measurement (per window), with both polarities handled:
//! 1. background level b = median of the window's border pixels; the hole is on the far side of
//!    the window's extreme value; hole level f = median of the pixels past the midpoint;
//! 2. rough blob: pixels with coverage w = (I − b)/(f − b) > 0.5, their centroid and area;
//! 3. sub-pixel centre and ellipse: *unclamped* coverage weights over a disc of radius
//!    r_blob + margin around the rough centre; centroid = Σw·x/Σw (exact for box-filtered edges,
//!    unbiased under zero-mean noise because the weights are not clamped), ellipse from the
//!    weighted second moments (a uniform ellipse with semi-axes a, b has moments a²/4, b²/4).
//!
//! Centre covariance: Var(c) = σ_w²·Σ(x − c)²/(Σw)² with σ_w = σ_I/|f − b| and σ_I from the
//! border pixels' MAD. Pixels: crate convention (centre of the top-left pixel at (0, 0)).

use crate::error::{invalid, Result};
use image::GrayImage;
use nalgebra::{Matrix2, Point2, SymmetricEigen};

/// Search settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoleSearch {
    /// Half-size of the square search window around each prediction (px).
    pub window_half_px: u32,
    /// Minimum |f − b| (grey levels).
    pub min_contrast: f64,
    /// Accepted blob area range (px²).
    pub min_area_px: f64,
    pub max_area_px: f64,
    /// Extra radius beyond the blob's equivalent radius for the sub-pixel moments (px);
    /// should cover the optical blur (≈ 3σ_blur + 1).
    pub margin_px: f64,
}

impl Default for HoleSearch {
    fn default() -> Self {
        HoleSearch { window_half_px: 40, min_contrast: 20.0, min_area_px: 12.0, max_area_px: 1e5, margin_px: 3.0 }
    }
}

/// One measured hole.
#[derive(Debug, Clone, PartialEq)]
pub struct HoleMeasurement {
    /// Centre (px).
    pub centre: Point2<f64>,
    /// Covariance of the centre (px²).
    pub covariance: Matrix2<f64>,
    /// Ellipse semi-axes (major, minor) in px and the major axis angle from +x (rad, towards +y).
    pub semi_axes: [f64; 2],
    pub angle: f64,
    /// Hole minus background grey level (negative for dark holes).
    pub contrast: f64,
}

/// Why a nominal cell has no hole.
#[derive(Debug, Clone, PartialEq)]
pub enum HoleRejection {
    OutsideImage,
    LowContrast { contrast: f64 },
    AreaOutOfRange { area_px: f64 },
    TouchesWindowBorder,
}

impl std::fmt::Display for HoleRejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HoleRejection::OutsideImage => write!(f, "search window leaves the image"),
            HoleRejection::LowContrast { contrast } => write!(f, "contrast {contrast:.1} grey levels is too low"),
            HoleRejection::AreaOutOfRange { area_px } => write!(f, "blob area {area_px:.1} px² outside the accepted range"),
            HoleRejection::TouchesWindowBorder => write!(f, "blob touches the search window border (prediction off or blob too large)"),
        }
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// Measure the hole near each predicted position (same order as `predicted`).
pub fn measure_holes(
    img: &GrayImage,
    predicted: &[Point2<f64>],
    search: &HoleSearch,
) -> Result<Vec<std::result::Result<HoleMeasurement, HoleRejection>>> {
    if search.window_half_px < 3 {
        return Err(invalid("window_half_px", "must be ≥ 3"));
    }
    for (k, p) in predicted.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Err(crate::error::VisionError::NonFinite { what: "predicted hole positions", index: k });
        }
    }
    Ok(predicted.iter().map(|p| measure_one(img, p, search)).collect())
}

fn measure_one(img: &GrayImage, p: &Point2<f64>, s: &HoleSearch) -> std::result::Result<HoleMeasurement, HoleRejection> {
    let h = s.window_half_px as i64;
    let (cx, cy) = (p.x.round() as i64, p.y.round() as i64);
    let (x0, y0, x1, y1) = (cx - h, cy - h, cx + h, cy + h);
    if x0 < 0 || y0 < 0 || x1 >= img.width() as i64 || y1 >= img.height() as i64 {
        return Err(HoleRejection::OutsideImage);
    }
    let at = |x: i64, y: i64| img.get_pixel(x as u32, y as u32)[0] as f64;
    let mut border: Vec<f64> = Vec::new();
    for x in x0..=x1 {
        border.push(at(x, y0));
        border.push(at(x, y1));
    }
    for y in y0 + 1..y1 {
        border.push(at(x0, y));
        border.push(at(x1, y));
    }
    let b = median(&mut border);
    let mut dev: Vec<f64> = border.iter().map(|v| (v - b).abs()).collect();
    let sigma_i = (1.4826 * median(&mut dev)).max(0.3); // quantisation floor ≈ 1/√12
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for y in y0..=y1 {
        for x in x0..=x1 {
            lo = lo.min(at(x, y));
            hi = hi.max(at(x, y));
        }
    }
    let extreme = if b - lo > hi - b { lo } else { hi };
    let mid = (b + extreme) / 2.0;
    let mut beyond: Vec<f64> = Vec::new();
    for y in y0..=y1 {
        for x in x0..=x1 {
            let v = at(x, y);
            if (v - mid) * (extreme - mid) > 0.0 {
                beyond.push(v);
            }
        }
    }
    if beyond.is_empty() {
        return Err(HoleRejection::LowContrast { contrast: 0.0 });
    }
    let f = median(&mut beyond);
    let contrast = f - b;
    if contrast.abs() < s.min_contrast {
        return Err(HoleRejection::LowContrast { contrast });
    }
    let w = |x: i64, y: i64| (at(x, y) - b) / contrast;
    // Rough blob (binary), connected to the pixel nearest the prediction's strongest response.
    let (mut n, mut sx, mut sy, mut on_border) = (0.0, 0.0, 0.0, false);
    for y in y0..=y1 {
        for x in x0..=x1 {
            if w(x, y) > 0.5 {
                n += 1.0;
                sx += x as f64;
                sy += y as f64;
                on_border |= x == x0 || x == x1 || y == y0 || y == y1;
            }
        }
    }
    if !(s.min_area_px..=s.max_area_px).contains(&n) {
        return Err(HoleRejection::AreaOutOfRange { area_px: n });
    }
    if on_border {
        return Err(HoleRejection::TouchesWindowBorder);
    }
    let (rx, ry) = (sx / n, sy / n);
    let radius = (n / std::f64::consts::PI).sqrt() + s.margin_px;
    if rx - radius < x0 as f64 || ry - radius < y0 as f64 || rx + radius > x1 as f64 || ry + radius > y1 as f64 {
        return Err(HoleRejection::TouchesWindowBorder);
    }
    // Sub-pixel moments with unclamped weights over the disc.
    let (mut sw, mut swx, mut swy) = (0.0, 0.0, 0.0);
    let mut pts = Vec::new();
    for y in (ry - radius).floor() as i64..=(ry + radius).ceil() as i64 {
        for x in (rx - radius).floor() as i64..=(rx + radius).ceil() as i64 {
            let (dx, dy) = (x as f64 - rx, y as f64 - ry);
            if dx * dx + dy * dy <= radius * radius {
                let wv = w(x, y);
                sw += wv;
                swx += wv * x as f64;
                swy += wv * y as f64;
                pts.push((x as f64, y as f64, wv));
            }
        }
    }
    let (mx, my) = (swx / sw, swy / sw);
    let (mut mxx, mut mxy, mut myy, mut vx, mut vy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y, wv) in &pts {
        let (dx, dy) = (x - mx, y - my);
        mxx += wv * dx * dx;
        mxy += wv * dx * dy;
        myy += wv * dy * dy;
        vx += dx * dx;
        vy += dy * dy;
    }
    let m = Matrix2::new(mxx, mxy, mxy, myy) / sw;
    let eig = SymmetricEigen::new(m);
    let (i_major, i_minor) = if eig.eigenvalues[0] >= eig.eigenvalues[1] { (0, 1) } else { (1, 0) };
    let major = eig.eigenvectors.column(i_major);
    let sigma_w = sigma_i / contrast.abs();
    let var = |v: f64| sigma_w * sigma_w * v / (sw * sw);
    Ok(HoleMeasurement {
        centre: Point2::new(mx, my),
        covariance: Matrix2::new(var(vx), 0.0, 0.0, var(vy)),
        semi_axes: [2.0 * eig.eigenvalues[i_major].max(0.0).sqrt(), 2.0 * eig.eigenvalues[i_minor].max(0.0).sqrt()],
        angle: major[1].atan2(major[0]),
        contrast,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_without_a_hole_are_rejected_with_a_reason() {
        let mut img = GrayImage::from_pixel(100, 100, image::Luma([200]));
        // A bright disc of radius 5 at (30.0, 30.0) on a dark patch (inverse contrast).
        for y in 10..51u32 {
            for x in 10..51u32 {
                let d = ((x as f64 - 30.0).powi(2) + (y as f64 - 30.0).powi(2)).sqrt();
                img.put_pixel(x, y, image::Luma([if d < 5.0 { 220 } else { 30 }]));
            }
        }
        let s = HoleSearch { window_half_px: 12, ..Default::default() };
        let r = measure_holes(&img, &[Point2::new(31.0, 29.0), Point2::new(75.0, 75.0), Point2::new(5.0, 50.0)], &s).unwrap();
        let h = r[0].as_ref().unwrap();
        assert!((h.centre.x - 30.0).abs() < 0.05 && (h.centre.y - 30.0).abs() < 0.05, "{:?}", h.centre);
        assert!(h.contrast > 150.0);
        assert!(matches!(r[1], Err(HoleRejection::LowContrast { .. })), "{:?}", r[1]);
        assert_eq!(r[2], Err(HoleRejection::OutsideImage));
        assert!(measure_holes(&img, &[Point2::new(f64::NAN, 0.0)], &s).is_err());
    }
}
