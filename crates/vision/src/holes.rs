//! Drilled holes / circular blobs at predicted positions (seed 000: a 6×6 grid of holes drilled
//! through a checkerboard over an inverse-contrast backing, so each hole shows the opposite
//! colour of its square). Each nominal cell is searched in a window around its predicted pixel
//! position, which is the assignment of holes to nominal grid cells; a cell with no acceptable
//! blob is rejected with a reason, never silently matched to a neighbour.
//!
//! Measurement (per window), with both polarities handled:
//! 1. background level b = median of the window's border pixels; polarity from the pixels
//!    around the prediction (else the window's stronger extreme); the pixels past the midpoint
//!    between b and the extreme of that polarity are the candidate pixels;
//! 2. rough blob: the 8-connected component of candidate pixels that holds the candidate pixel
//!    nearest the prediction; hole level f = median of its pixels, coverage w = (I − b)/(f − b);
//!    its centroid and area;
//! 3. other blobs in the window (a neighbouring hole reaching in, a burr, dirt): ignored while
//!    they stay clear of the disc of step 4 by more than the margin (they do not enter its sums,
//!    so they cannot move the centre); otherwise the cell is rejected ([`HoleRejection::BlobTooClose`]),
//!    as it is when a second hole-sized blob lies wholly in the window ([`HoleRejection::SeveralBlobs`]).
//!    Why reject rather than mask: a blob inside the blur margin overlaps the hole's own blurred
//!    edge, so no mask removes it without cutting the edge the centroid relies on; a biased
//!    centre reported as good is invisible downstream, a rejected cell is not;
//! 4. sub-pixel centre and ellipse: *unclamped* coverage weights over a disc of radius
//!    r_blob + margin around the rough centre; centroid = Σw·x/Σw (exact for box-filtered edges,
//!    unbiased under zero-mean noise because the weights are not clamped), ellipse from the
//!    weighted second moments (a uniform ellipse with semi-axes a, b has moments a²/4, b²/4).
//!
//! Centre covariance: Var(c) = σ_w²·Σ(x − c)²/(Σw)² with σ_w = σ_I/|f − b| and σ_I from the
//! border pixels' MAD, plus [`CENTRE_FLOOR_PX`]² per axis. Pixels: crate convention (centre of
//! the top-left pixel at (0, 0)).

use crate::error::{invalid, Result};
use image::GrayImage;
use nalgebra::{Matrix2, Point2, SymmetricEigen};

/// The least σ (px, per axis) a hole centre is given: moments over a sharp, high-contrast hole
/// state a few thousandths of a pixel from the image noise alone, but the sampling of its edge
/// by the pixels, blur and the sensor's response leave ~0.02–0.03 px (measured on
/// tests/py/router_photo.py's OpenCV-drawn plates: 2–3 µm at 0.1 mm/px, where the noise term
/// alone stated 5–7× less).
pub const CENTRE_FLOOR_PX: f64 = 0.03;

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
        HoleSearch {
            window_half_px: 40,
            min_contrast: 20.0,
            min_area_px: 12.0,
            max_area_px: 1e5,
            margin_px: 3.0,
        }
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
    LowContrast {
        contrast: f64,
    },
    AreaOutOfRange {
        area_px: f64,
    },
    TouchesWindowBorder,
    /// Another hole-sized blob (≥ half the hole's area) lies wholly inside the search window:
    /// the assignment to the nominal cell would be a guess.
    SeveralBlobs {
        blobs: usize,
    },
    /// Another blob (burr, dirt, a neighbour's edge) comes within `margin_px` of the disc the
    /// centre is measured over (`gap_px` from its edge), so it would bias the centre.
    BlobTooClose {
        gap_px: f64,
    },
}

impl std::fmt::Display for HoleRejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HoleRejection::OutsideImage => write!(f, "search window leaves the image"),
            HoleRejection::LowContrast { contrast } => {
                write!(f, "contrast {contrast:.1} grey levels is too low")
            }
            HoleRejection::AreaOutOfRange { area_px } => {
                write!(f, "blob area {area_px:.1} px² outside the accepted range")
            }
            HoleRejection::TouchesWindowBorder => write!(
                f,
                "blob touches the search window border (prediction off or blob too large)"
            ),
            HoleRejection::SeveralBlobs { blobs } => write!(
                f,
                "{blobs} hole-sized blobs in the search window: which one is the hole is ambiguous"
            ),
            HoleRejection::BlobTooClose { gap_px } => write!(
                f,
                "another blob {gap_px:.1} px from the measured disc would bias the centre"
            ),
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
            return Err(crate::error::VisionError::NonFinite {
                what: "predicted hole positions",
                index: k,
            });
        }
    }
    Ok(predicted
        .iter()
        .map(|p| measure_one(img, p, search))
        .collect())
}

/// One 8-connected set of window pixels with coverage > 0.5.
struct Component {
    pixels: Vec<(i64, i64)>,
    on_border: bool,
}

/// The 8-connected components of `on` (row-major, `side` × `side`, window origin `(x0, y0)`).
fn components(on: &[bool], side: usize, x0: i64, y0: i64) -> (Vec<Component>, Vec<usize>) {
    const NONE: usize = usize::MAX;
    let mut label = vec![NONE; on.len()];
    let mut comps = Vec::new();
    let mut stack = Vec::new();
    for start in 0..on.len() {
        if !on[start] || label[start] != NONE {
            continue;
        }
        let id = comps.len();
        let mut c = Component {
            pixels: Vec::new(),
            on_border: false,
        };
        label[start] = id;
        stack.push(start);
        while let Some(k) = stack.pop() {
            let (u, v) = (k % side, k / side);
            c.pixels.push((x0 + u as i64, y0 + v as i64));
            c.on_border |= u == 0 || v == 0 || u == side - 1 || v == side - 1;
            for dv in -1i64..=1 {
                for du in -1i64..=1 {
                    let (nu, nv) = (u as i64 + du, v as i64 + dv);
                    if nu < 0 || nv < 0 || nu >= side as i64 || nv >= side as i64 {
                        continue;
                    }
                    let n = nv as usize * side + nu as usize;
                    if on[n] && label[n] == NONE {
                        label[n] = id;
                        stack.push(n);
                    }
                }
            }
        }
        comps.push(c);
    }
    (comps, label)
}

/// The square search window around a prediction (pixel bounds, inclusive).
struct Window<'i> {
    img: &'i GrayImage,
    x0: i64,
    y0: i64,
    x1: i64,
    y1: i64,
}

impl Window<'_> {
    fn at(&self, x: i64, y: i64) -> f64 {
        self.img.get_pixel(x as u32, y as u32)[0] as f64
    }
    /// Side length (px).
    fn side(&self) -> usize {
        (self.x1 - self.x0 + 1) as usize
    }
    fn contains(&self, x: i64, y: i64) -> bool {
        x >= self.x0 && y >= self.y0 && x <= self.x1 && y <= self.y1
    }
}

/// The hole at `p`, measured in its search window: background, candidate pixels, rough blob
/// (rejected when another blob is too close), sub-pixel centre and ellipse (the module's doc
/// gives the steps).
fn measure_one(
    img: &GrayImage,
    p: &Point2<f64>,
    s: &HoleSearch,
) -> std::result::Result<HoleMeasurement, HoleRejection> {
    let h = s.window_half_px as i64;
    let (cx, cy) = (p.x.round() as i64, p.y.round() as i64);
    let (x0, y0, x1, y1) = (cx - h, cy - h, cx + h, cy + h);
    if x0 < 0 || y0 < 0 || x1 >= img.width() as i64 || y1 >= img.height() as i64 {
        return Err(HoleRejection::OutsideImage);
    }
    let win = Window {
        img,
        x0,
        y0,
        x1,
        y1,
    };
    let (b, sigma_i) = background(&win);
    let on = candidate_pixels(&win, (cx, cy), b, s);
    if !on.contains(&true) {
        return Err(HoleRejection::LowContrast { contrast: 0.0 });
    }
    // Rough blob: the connected component of the above-threshold pixel nearest the prediction.
    // (Taking every such pixel of the window merged a neighbouring hole, burr or dirt into the
    // hole and moved its centre.)
    let side = win.side();
    let (comps, label) = components(&on, side, x0, y0);
    let seed = (0..on.len())
        .filter(|&k| on[k])
        .min_by(|&i, &j| {
            let xy = |k: usize| (x0 + (k % side) as i64, y0 + (k / side) as i64);
            dist2(xy(i), p).total_cmp(&dist2(xy(j), p))
        })
        .expect("some pixel is on");
    let hole_id = label[seed];
    let hole = &comps[hole_id];
    let mut levels: Vec<f64> = hole.pixels.iter().map(|&(x, y)| win.at(x, y)).collect();
    let f = median(&mut levels);
    let contrast = f - b;
    if contrast.abs() < s.min_contrast {
        return Err(HoleRejection::LowContrast { contrast });
    }
    let n = hole.pixels.len() as f64;
    if !(s.min_area_px..=s.max_area_px).contains(&n) {
        return Err(HoleRejection::AreaOutOfRange { area_px: n });
    }
    if hole.on_border {
        return Err(HoleRejection::TouchesWindowBorder);
    }
    // Another hole-sized blob wholly inside the window: two candidates for one nominal cell;
    // which one is the hole is a guess, so the cell is rejected rather than possibly matched
    // to the wrong blob.
    let rivals = comps
        .iter()
        .enumerate()
        .filter(|&(k, c)| {
            k != hole_id && !c.on_border && c.pixels.len() as f64 >= s.min_area_px.max(0.5 * n)
        })
        .count();
    if rivals > 0 {
        return Err(HoleRejection::SeveralBlobs { blobs: rivals + 1 });
    }
    let (rx, ry) = (
        hole.pixels.iter().map(|q| q.0 as f64).sum::<f64>() / n,
        hole.pixels.iter().map(|q| q.1 as f64).sum::<f64>() / n,
    );
    let radius = (n / std::f64::consts::PI).sqrt() + s.margin_px;
    if rx - radius < x0 as f64
        || ry - radius < y0 as f64
        || rx + radius > x1 as f64
        || ry + radius > y1 as f64
    {
        return Err(HoleRejection::TouchesWindowBorder);
    }
    let rough = Point2::new(rx, ry);
    let others = comps
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != hole_id)
        .map(|(_, c)| c);
    let gap = clearance(&win, others, rough, radius, (b, sigma_i, contrast), s);
    if gap < s.margin_px {
        return Err(HoleRejection::BlobTooClose {
            gap_px: gap.max(0.0),
        });
    }
    Ok(subpixel_ellipse(&win, rough, radius, b, sigma_i, contrast))
}

fn dist2((x, y): (i64, i64), q: &Point2<f64>) -> f64 {
    (x as f64 - q.x).powi(2) + (y as f64 - q.y).powi(2)
}

/// The window's background level (median of its border pixels) and the pixels' noise σ_I (from
/// the border's MAD, floored at the quantisation's).
fn background(win: &Window) -> (f64, f64) {
    let (x0, y0, x1, y1) = (win.x0, win.y0, win.x1, win.y1);
    let mut border: Vec<f64> = Vec::new();
    for x in x0..=x1 {
        border.push(win.at(x, y0));
        border.push(win.at(x, y1));
    }
    for y in y0 + 1..y1 {
        border.push(win.at(x0, y));
        border.push(win.at(x1, y));
    }
    let b = median(&mut border);
    let mut dev: Vec<f64> = border.iter().map(|v| (v - b).abs()).collect();
    let sigma_i = (1.4826 * median(&mut dev)).max(0.3); // quantisation floor ≈ 1/√12
    (b, sigma_i)
}

/// The window's pixels past the midpoint between the background `b` and the extreme of the
/// hole's polarity (row by row).
fn candidate_pixels(win: &Window, (cx, cy): (i64, i64), b: f64, s: &HoleSearch) -> Vec<bool> {
    let (x0, y0, x1, y1) = (win.x0, win.y0, win.x1, win.y1);
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for y in y0..=y1 {
        for x in x0..=x1 {
            lo = lo.min(win.at(x, y));
            hi = hi.max(win.at(x, y));
        }
    }
    // Polarity: from the pixels around the prediction when they clearly differ from the
    // background (so a brighter burr cannot turn the search for a dark hole into a search for
    // bright blobs), else from the window's stronger extreme.
    let mut near: Vec<f64> = (cy - 2..=cy + 2)
        .flat_map(|y| (cx - 2..=cx + 2).map(move |x| (x, y)))
        .map(|(x, y)| win.at(x, y))
        .collect();
    let near = median(&mut near);
    let dark = if (near - b).abs() >= s.min_contrast {
        near < b
    } else {
        b - lo > hi - b
    };
    let extreme = if dark { lo } else { hi };
    let mid = (b + extreme) / 2.0;
    (y0..=y1)
        .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
        .map(|(x, y)| (win.at(x, y) - mid) * (extreme - mid) > 0.0)
        .collect()
}

/// The clearance (px) between the moment disc (`radius` about `rough`) and the nearest other
/// blob (`others`) or pixel of the opposite polarity; `levels`: background, σ_I, contrast.
fn clearance<'c>(
    win: &Window,
    others: impl Iterator<Item = &'c Component>,
    rough: Point2<f64>,
    radius: f64,
    (b, sigma_i, contrast): (f64, f64, f64),
    s: &HoleSearch,
) -> f64 {
    // Any other blob (either polarity) whose pixels or blurred edge (margin) reach the moment
    // disc would pull the centre towards it; masking it would also cut the hole's own blurred
    // edge, so the hole is rejected. Blobs farther away do not enter the sums and are ignored.
    let (rx, ry) = (rough.x, rough.y);
    let reach = radius + s.margin_px;
    let mut gap = f64::INFINITY;
    for c in others {
        for &q in &c.pixels {
            gap = gap.min(dist2(q, &rough).sqrt() - radius);
        }
    }
    // Opposite polarity (a reflection on a burr next to a dark hole): not in the components,
    // and bounded by the grey scale (255 is 55 levels above a 200 background), so any clear
    // deviation counts: more than 10 % of the contrast, half of min_contrast and 4 σ_I.
    let opposite = (0.1 * contrast.abs())
        .max(0.5 * s.min_contrast)
        .max(4.0 * sigma_i);
    for y in (ry - reach).floor() as i64..=(ry + reach).ceil() as i64 {
        for x in (rx - reach).floor() as i64..=(rx + reach).ceil() as i64 {
            if win.contains(x, y) && (win.at(x, y) - b) * contrast.signum() < -opposite {
                gap = gap.min(dist2((x, y), &rough).sqrt() - radius);
            }
        }
    }
    gap
}

/// The sub-pixel centre and ellipse from unclamped coverage weights over the disc of `radius`
/// about `rough`, and the centre's covariance.
fn subpixel_ellipse(
    win: &Window,
    rough: Point2<f64>,
    radius: f64,
    b: f64,
    sigma_i: f64,
    contrast: f64,
) -> HoleMeasurement {
    let (rx, ry) = (rough.x, rough.y);
    let w = |x: i64, y: i64| (win.at(x, y) - b) / contrast;
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
    let (i_major, i_minor) = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let major = eig.eigenvectors.column(i_major);
    let sigma_w = sigma_i / contrast.abs();
    let var = |v: f64| sigma_w * sigma_w * v / (sw * sw) + CENTRE_FLOOR_PX * CENTRE_FLOOR_PX;
    HoleMeasurement {
        centre: Point2::new(mx, my),
        covariance: Matrix2::new(var(vx), 0.0, 0.0, var(vy)),
        semi_axes: [
            2.0 * eig.eigenvalues[i_major].max(0.0).sqrt(),
            2.0 * eig.eigenvalues[i_minor].max(0.0).sqrt(),
        ],
        angle: major[1].atan2(major[0]),
        contrast,
    }
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
        let s = HoleSearch {
            window_half_px: 12,
            ..Default::default()
        };
        let r = measure_holes(
            &img,
            &[
                Point2::new(31.0, 29.0),
                Point2::new(75.0, 75.0),
                Point2::new(5.0, 50.0),
            ],
            &s,
        )
        .unwrap();
        let h = r[0].as_ref().unwrap();
        assert!(
            (h.centre.x - 30.0).abs() < 0.05 && (h.centre.y - 30.0).abs() < 0.05,
            "{:?}",
            h.centre
        );
        assert!(h.contrast > 150.0);
        assert!(
            matches!(r[1], Err(HoleRejection::LowContrast { .. })),
            "{:?}",
            r[1]
        );
        assert_eq!(r[2], Err(HoleRejection::OutsideImage));
        assert!(measure_holes(&img, &[Point2::new(f64::NAN, 0.0)], &s).is_err());
    }
}
