//! Digital-twin renderer: planar targets (ArUco markers, checkerboards, drilled holes) seen by a pinhole camera
//! with Brown–Conrady distortion, with the exact ground-truth pixel positions of their corners.
//!
//! Target frame: the target is the plane z = 0, x to the right, y down as printed (so a front view
//! with the identity rotation shows it upright). Lengths in metres. The pose maps target → camera.
//!
//! Image formation: each pixel integrates the target's reflectance over its unit square (box
//! filter, the pixel convention of the crate doc). The target's boundaries are traced through
//! the camera into an edge mask ([`edges`]): pixels an edge may cross are supersampled on an
//! s×s grid — or, where a single boundary crosses the pixel, shaded with its exact area split
//! ([`coverage`]) — and each row's runs of unmarked pixels, which see one reflectance, are
//! sampled once.
//! (When the whole image does not see the target plane — horizon or lens limit in view — or the
//! tracing budget runs out, every pixel is supersampled instead: s² samples per pixel, 16–64×
//! slower, but no edge can slip between samples of a flatness test.)
//! Then optional Gaussian blur (optics; computed only near edges, [`edge_blur`]), a
//! multiplicative lighting gradient, additive Gaussian noise ([`normal_table`]), and rounding
//! to u8. Cost: ~1 sample per run plus s² per edge pixel, not ~2 per pixel.

use crate::aruco::Dictionary;
use crate::camera::{pixel_to_normalized, project, CameraModel};
use crate::error::{invalid, Result};
use image::GrayImage;
use nalgebra::{Isometry3, Point2, Point3, Vector3};
use rand::{RngCore, SeedableRng};

mod coverage;
mod edge_blur;
mod edges;
mod normal_table;

/// A printed feature on the target plane.
#[derive(Debug, Clone)]
pub enum TargetItem {
    /// ArUco marker, upright, its outer black border's top-left corner at `top_left` (m),
    /// outer side `side` (m), border `border_bits` cells wide.
    Marker {
        dictionary: Dictionary,
        id: usize,
        top_left: [f64; 2],
        side: f64,
        border_bits: u32,
    },
    /// Checkerboard of `squares_x` × `squares_y` squares of side `square` (m); the top-left square
    /// is black, or white when `top_left_black` is false (a board whose front-left square is
    /// black and has an even number of rows, seen with its back at the top).
    Checkerboard {
        top_left: [f64; 2],
        square: f64,
        squares_x: u32,
        squares_y: u32,
        top_left_black: bool,
    },
    /// A drilled through-hole of `diameter` (m) centred at `centre` (m), seen against an
    /// inverse-contrast backing (seed 000): it shows the opposite of what lies beneath it
    /// (black under a white square, white under a black one).
    Hole { centre: [f64; 2], diameter: f64 },
    /// A filled rectangle, black or white: a printer's bed, a card's paper, a tile's quiet zone.
    Rectangle {
        top_left: [f64; 2],
        size: [f64; 2],
        white: bool,
    },
    /// A filled disc, black or white: a printed dot's top.
    Disc {
        centre: [f64; 2],
        diameter: f64,
        white: bool,
    },
}

/// Bit of cell (row r, column c) of a marker with an n × n payload inside a `border`-cell black
/// border: 0 (black) on the border, else the code's bit, row-major from the top-left payload
/// cell in the most significant bit (OpenCV's layout). Shared by the shading and the edge
/// tracer, so both see the same cells.
fn marker_cell(code: u64, n: u32, border: u32, r: u32, c: u32) -> u64 {
    let inner = |k: u32| k >= border && k < n + border;
    if inner(r) && inner(c) {
        (code >> (n * n - 1 - ((r - border) * n + (c - border)))) & 1
    } else {
        0
    }
}

/// White plane carrying items (later items paint over earlier ones).
#[derive(Debug, Clone, Default)]
pub struct PlanarTarget {
    pub items: Vec<TargetItem>,
}

/// How to form the image. Grey levels are on the 0–255 scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Samples per pixel axis on pixels that straddle an edge (≥ 1).
    pub supersampling: u32,
    /// Gaussian blur standard deviation, pixels (0 = none).
    pub blur_sigma_px: f64,
    /// Additive Gaussian noise standard deviation, grey levels (0 = none).
    pub noise_sigma: f64,
    /// Grey level of black ink and of white paper under unit illumination.
    pub black_level: f64,
    pub white_level: f64,
    /// Relative illumination change across the image width and height: illumination
    /// = 1 + gx·(u − w/2)/w + gy·(v − h/2)/h.
    pub gradient: [f64; 2],
    /// Grey level where the plane is not seen (behind the camera or facing away).
    pub background: f64,
    pub seed: u64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            supersampling: 16,
            blur_sigma_px: 0.0,
            noise_sigma: 0.0,
            black_level: 20.0,
            white_level: 235.0,
            gradient: [0.0, 0.0],
            background: 128.0,
            seed: 1,
        }
    }
}

/// Ground truth for one marker: corners in OpenCV order (top-left, top-right, bottom-right,
/// bottom-left of the printed marker), pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerTruth {
    pub id: usize,
    pub corners: [Point2<f64>; 4],
}

/// A rendered view and its ground truth.
#[derive(Debug, Clone)]
pub struct RenderedView {
    pub image: GrayImage,
    pub markers: Vec<MarkerTruth>,
    /// Per checkerboard item: inner corners row-major from the top-left, (squares_x−1) per row.
    pub checkerboard_corners: Vec<Vec<Point2<f64>>>,
}

impl TargetItem {
    /// Reflectance at target point (x, y): Some(0.0) black, Some(1.0) white, None = not on item.
    fn reflectance(&self, x: f64, y: f64) -> Option<f64> {
        match self {
            TargetItem::Marker {
                dictionary,
                id,
                top_left,
                side,
                border_bits,
            } => {
                let cells = dictionary.marker_size as u32 + 2 * border_bits;
                let u = (x - top_left[0]) / side * cells as f64;
                let v = (y - top_left[1]) / side * cells as f64;
                if !(0.0..cells as f64).contains(&u) || !(0.0..cells as f64).contains(&v) {
                    return None;
                }
                let code = dictionary.code(*id).ok()?;
                Some(marker_cell(
                    code,
                    dictionary.marker_size as u32,
                    *border_bits,
                    v as u32,
                    u as u32,
                ) as f64)
            }
            TargetItem::Checkerboard {
                top_left,
                square,
                squares_x,
                squares_y,
                top_left_black,
            } => {
                let u = (x - top_left[0]) / square;
                let v = (y - top_left[1]) / square;
                if !(0.0..*squares_x as f64).contains(&u) || !(0.0..*squares_y as f64).contains(&v)
                {
                    return None;
                }
                Some(if ((u as u32 + v as u32) % 2 == 0) == *top_left_black {
                    0.0
                } else {
                    1.0
                })
            }
            // Depends on what is beneath: resolved by PlanarTarget::reflectance.
            TargetItem::Hole { .. } => None,
            TargetItem::Rectangle {
                top_left,
                size,
                white,
            } => ((top_left[0]..top_left[0] + size[0]).contains(&x)
                && (top_left[1]..top_left[1] + size[1]).contains(&y))
            .then_some(if *white { 1.0 } else { 0.0 }),
            TargetItem::Disc {
                centre,
                diameter,
                white,
            } => {
                let (dx, dy) = (x - centre[0], y - centre[1]);
                (dx * dx + dy * dy < diameter * diameter / 4.0).then_some(if *white {
                    1.0
                } else {
                    0.0
                })
            }
        }
    }

    fn validate(&self) -> Result<()> {
        match self {
            TargetItem::Marker {
                dictionary,
                id,
                side,
                border_bits,
                ..
            } => {
                dictionary.code(*id)?;
                if !(side.is_finite() && *side > 0.0) {
                    return Err(invalid("Marker.side", format!("must be > 0, got {side}")));
                }
                if *border_bits == 0 {
                    return Err(invalid("Marker.border_bits", "must be ≥ 1"));
                }
            }
            TargetItem::Checkerboard {
                square,
                squares_x,
                squares_y,
                ..
            } => {
                if !(square.is_finite() && *square > 0.0) {
                    return Err(invalid(
                        "Checkerboard.square",
                        format!("must be > 0, got {square}"),
                    ));
                }
                if *squares_x < 2 || *squares_y < 2 {
                    return Err(invalid("Checkerboard.squares", "need at least 2×2 squares"));
                }
            }
            TargetItem::Hole { centre, diameter }
            | TargetItem::Disc {
                centre, diameter, ..
            } => {
                if !(diameter.is_finite() && *diameter > 0.0) {
                    return Err(invalid(
                        "Hole/Disc.diameter",
                        format!("must be > 0, got {diameter}"),
                    ));
                }
                if !(centre[0].is_finite() && centre[1].is_finite()) {
                    return Err(invalid("Hole/Disc.centre", "must be finite"));
                }
            }
            TargetItem::Rectangle { top_left, size, .. } => {
                if !(top_left.iter().all(|v| v.is_finite())
                    && size.iter().all(|v| v.is_finite() && *v > 0.0))
                {
                    return Err(invalid(
                        "Rectangle",
                        format!("needs a finite corner and sides > 0, got {top_left:?} {size:?}"),
                    ));
                }
            }
        }
        Ok(())
    }
}

impl PlanarTarget {
    fn reflectance(&self, x: f64, y: f64) -> f64 {
        Self::reflectance_of(&self.items, x, y)
    }

    /// Topmost item at (x, y); a hole inverts whatever the items below it show there.
    fn reflectance_of(items: &[TargetItem], x: f64, y: f64) -> f64 {
        for (k, it) in items.iter().enumerate().rev() {
            if let TargetItem::Hole { centre, diameter } = it {
                let (dx, dy) = (x - centre[0], y - centre[1]);
                if dx * dx + dy * dy < diameter * diameter / 4.0 {
                    return 1.0 - Self::reflectance_of(&items[..k], x, y);
                }
            } else if let Some(r) = it.reflectance(x, y) {
                return r;
            }
        }
        1.0
    }
}

/// Geometry of one view: pixel → target reflectance (NaN where the plane is not seen).
struct ViewGeometry<'a> {
    camera: &'a CameraModel,
    target: &'a PlanarTarget,
    origin: Vector3<f64>,          // camera centre in the target frame
    rot_t: nalgebra::Matrix3<f64>, // camera → target rotation
}

impl<'a> ViewGeometry<'a> {
    fn new(camera: &'a CameraModel, target: &'a PlanarTarget, pose: &Isometry3<f64>) -> Self {
        let rot_t = pose.rotation.to_rotation_matrix().matrix().transpose();
        ViewGeometry {
            camera,
            target,
            origin: -(rot_t * pose.translation.vector),
            rot_t,
        }
    }

    /// Target-plane point seen along the ray of ideal normalised coordinates (x, y), if the
    /// ray meets the plane in front of the camera.
    fn hit(&self, x: f64, y: f64) -> Option<Vector3<f64>> {
        let dir = self.rot_t * Vector3::new(x, y, 1.0);
        if dir.z.abs() < 1e-15 {
            return None;
        }
        let lambda = -self.origin.z / dir.z;
        if lambda <= 0.0 {
            return None;
        }
        Some(self.origin + lambda * dir)
    }

    fn sample(&self, u: f64, v: f64) -> f64 {
        let Some((x, y)) = pixel_to_normalized(self.camera, u, v) else {
            return f64::NAN;
        };
        match self.hit(x, y) {
            Some(p) => self.target.reflectance(p.x, p.y),
            None => f64::NAN,
        }
    }

    /// Mean reflectance over pixel (i, j) from s×s samples; unseen samples count as `bg`
    /// (the background level as a reflectance); NaN if no sample sees the plane.
    /// A pixel one boundary crosses gets its exact area split instead ([`coverage`]): the
    /// grid alone rounds a boundary parallel to its columns to 1/s px.
    fn supersample(&self, i: usize, j: usize, s: usize, bg: f64) -> f64 {
        if let Some(mean) =
            coverage::one_boundary_mean(&|u, v| self.sample(u, v), i as f64, j as f64, s)
        {
            return mean;
        }
        let mut acc = 0.0;
        let mut n_nan = 0usize;
        for b in 0..s {
            for a in 0..s {
                let u = i as f64 - 0.5 + (a as f64 + 0.5) / s as f64;
                let v = j as f64 - 0.5 + (b as f64 + 0.5) / s as f64;
                let r = self.sample(u, v);
                if r.is_nan() {
                    n_nan += 1;
                } else {
                    acc += r;
                }
            }
        }
        if n_nan == s * s {
            f64::NAN
        } else {
            (acc + n_nan as f64 * bg) / (s * s) as f64
        }
    }

    /// Grey level of every pixel before blur and noise (`grey_of` maps a reflectance, NaN for
    /// unseen, to grey). With the edge mask, flat runs of a row are sampled once and mask
    /// pixels supersampled s×s; without it (tracing failed), every pixel is supersampled. The
    /// fast path must give the image of the slow one (tested below).
    fn shade(
        &self,
        mask: Option<&[u8]>,
        s: usize,
        bg: f64,
        grey_of: &impl Fn(f64) -> f64,
        grey: &mut [f64],
    ) {
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        match mask {
            Some(mask) => {
                for j in 0..h {
                    let (row_mask, row) =
                        (&mask[j * w..(j + 1) * w], &mut grey[j * w..(j + 1) * w]);
                    let mut i = 0;
                    while i < w {
                        if row_mask[i] == 0 {
                            let start = i;
                            i += row_mask[i..].iter().position(|&m| m != 0).unwrap_or(w - i);
                            row[start..i].fill(grey_of(self.sample(start as f64, j as f64)));
                        } else {
                            row[i] = grey_of(self.supersample(i, j, s, bg));
                            i += 1;
                        }
                    }
                }
            }
            None => {
                // No edge mask: every pixel is supersampled. Slower (s² samples per pixel), but a
                // cheaper flatness test (corners and centre alike) misses an edge that pokes into a
                // pixel between its samples; this path is only taken when the plane's horizon or
                // a feature behind the camera is in view.
                for (k, g) in grey.iter_mut().enumerate() {
                    *g = grey_of(self.supersample(k % w, k / w, s, bg));
                }
            }
        }
    }

    /// Edge mask of the view ([`edges`]), or None when the whole image does not see the
    /// target plane (checked along the image border: the visible part of the normalised plane
    /// is a half-plane, so if the border sees it, so does everything inside) or tracing failed.
    fn edge_mask(&self, pose: &Isometry3<f64>, buffer: Vec<u8>) -> Option<Vec<u8>> {
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        let mut bbox = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let border = (0..=w)
            .flat_map(|i| [(i as f64 - 0.5, -0.5), (i as f64 - 0.5, h as f64 - 0.5)])
            .chain(
                (0..=h).flat_map(|j| [(-0.5, j as f64 - 0.5), (w as f64 - 0.5, j as f64 - 0.5)]),
            );
        for (u, v) in border {
            let (x, y) = pixel_to_normalized(self.camera, u, v)?;
            self.hit(x, y)?;
            bbox = [
                bbox[0].min(x),
                bbox[1].max(x),
                bbox[2].min(y),
                bbox[3].max(y),
            ];
        }
        // Margin for the border between its samples: 1 % of the box plus two pixels.
        let gx = 0.01 * (bbox[1] - bbox[0]) + 2.0 / self.camera.fx;
        let gy = 0.01 * (bbox[3] - bbox[2]) + 2.0 / self.camera.fy;
        let bbox = [bbox[0] - gx, bbox[1] + gx, bbox[2] - gy, bbox[3] + gy];
        let rot = *pose.rotation.to_rotation_matrix().matrix();
        let mut tracer =
            edges::EdgeTracer::new(self.camera, rot, pose.translation.vector, bbox, buffer);
        for b in edges::boundaries(&self.target.items) {
            if !tracer.trace(&b) {
                return None;
            }
        }
        Some(tracer.mask)
    }
}

thread_local! {
    /// Grey image and edge mask buffers reused by the next render on this thread.
    static SCRATCH: std::cell::RefCell<(Vec<f64>, Vec<u8>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// Render `target` seen by `camera` with `pose` (target → camera).
pub fn render_view(
    camera: &CameraModel,
    pose: &Isometry3<f64>,
    target: &PlanarTarget,
    settings: &RenderSettings,
) -> Result<RenderedView> {
    for it in &target.items {
        it.validate()?;
    }
    if settings.supersampling == 0 || settings.supersampling > 64 {
        return Err(invalid(
            "supersampling",
            format!("must be 1..=64, got {}", settings.supersampling),
        ));
    }
    for (name, v) in [
        ("blur_sigma_px", settings.blur_sigma_px),
        ("noise_sigma", settings.noise_sigma),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(name, format!("must be finite and ≥ 0, got {v}")));
        }
    }
    let (w, h) = (camera.width as usize, camera.height as usize);
    let geom = ViewGeometry::new(camera, target, pose);
    let s = settings.supersampling as usize;
    let span = settings.white_level - settings.black_level;
    // Unseen samples show the background level, expressed as a reflectance.
    let bg = (settings.background - settings.black_level) / span;
    // Grey levels before blurring, so unseen regions blur like anything else.
    let grey_of = |r: f64| {
        if r.is_nan() {
            settings.background
        } else {
            settings.black_level + span * r
        }
    };
    // Per-thread scratch: a 5 MP frame's grey image is 40 MB, and mapping fresh pages for it
    // on every frame cost more than filling it.
    let (mut grey, mask_buf) = SCRATCH.with(|s| std::mem::take(&mut *s.borrow_mut()));
    // Every pixel is written below, so a reused buffer needs no clearing.
    grey.resize(w * h, 0.0);
    let mask = geom.edge_mask(pose, mask_buf);
    geom.shade(mask.as_deref(), s, bg, &grey_of, &mut grey);
    if settings.blur_sigma_px > 0.0 {
        match &mask {
            Some(mask) => edge_blur::blur_near_edges(&mut grey, mask, w, h, settings.blur_sigma_px),
            None => grey = crate::filters::gaussian_blur_f64(&grey, w, h, settings.blur_sigma_px),
        }
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(settings.seed);
    let normal = normal_table::table();
    let per_draw = (64 / normal_table::BITS) as usize;
    let index_mask = (1u64 << normal_table::BITS) - 1;
    let mut pixels = vec![0u8; w * h];
    // Illumination = 1 + column term + row term (the formula of RenderSettings::gradient).
    let column_term: Vec<f64> = (0..w)
        .map(|i| settings.gradient[0] * (i as f64 - w as f64 / 2.0) / w as f64)
        .collect();
    // Round half up after clamping (NaN → 0): a truncating cast, not a libm call.
    let to_u8 = |g: f64| (g.clamp(0.0, 255.0) + 0.5) as u8;
    for j in 0..h {
        let row_term = settings.gradient[1] * (j as f64 - h as f64 / 2.0) / h as f64;
        let (src, dst) = (&grey[j * w..(j + 1) * w], &mut pixels[j * w..(j + 1) * w]);
        if settings.noise_sigma > 0.0 {
            // One 64-bit draw per `per_draw` pixels of a row (a row's last draw may have
            // bits left over; they are dropped).
            for ((s4, d4), c4) in src
                .chunks(per_draw)
                .zip(dst.chunks_mut(per_draw))
                .zip(column_term.chunks(per_draw))
            {
                let mut bits = rng.next_u64();
                for ((g, d), c) in s4.iter().zip(d4).zip(c4) {
                    let noise = normal[(bits & index_mask) as usize] as f64;
                    bits >>= normal_table::BITS;
                    *d = to_u8(g * (1.0 + c + row_term) + settings.noise_sigma * noise);
                }
            }
        } else {
            for ((g, d), c) in src.iter().zip(dst.iter_mut()).zip(&column_term) {
                *d = to_u8(g * (1.0 + c + row_term));
            }
        }
    }
    SCRATCH.with(|s| *s.borrow_mut() = (grey, mask.unwrap_or_default()));
    let img = GrayImage::from_raw(camera.width, camera.height, pixels)
        .expect("the buffer holds width × height pixels");
    // Ground truth.
    let mut markers = Vec::new();
    let mut checkerboard_corners = Vec::new();
    let project = |x: f64, y: f64| -> Result<Point2<f64>> {
        project(camera, pose, &Point3::new(x, y, 0.0)).ok_or_else(|| {
            crate::error::VisionError::NoSolution {
                what: "render ground truth",
                reason: format!("target point ({x}, {y}) is behind the camera"),
            }
        })
    };
    for it in &target.items {
        match it {
            TargetItem::Marker {
                id,
                top_left: [x, y],
                side,
                ..
            } => markers.push(MarkerTruth {
                id: *id,
                corners: [
                    project(*x, *y)?,
                    project(x + side, *y)?,
                    project(x + side, y + side)?,
                    project(*x, y + side)?,
                ],
            }),
            TargetItem::Checkerboard {
                top_left: [x, y],
                square,
                squares_x,
                squares_y,
                ..
            } => {
                let mut pts = Vec::new();
                for r in 1..*squares_y {
                    for c in 1..*squares_x {
                        pts.push(project(x + c as f64 * square, y + r as f64 * square)?);
                    }
                }
                checkerboard_corners.push(pts);
            }
            TargetItem::Hole { .. } | TargetItem::Rectangle { .. } | TargetItem::Disc { .. } => {}
        }
    }
    Ok(RenderedView {
        image: img,
        markers,
        checkerboard_corners,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Distortion;

    /// Markers, a checkerboard and holes on an oblique, distorted view.
    fn scene() -> (CameraModel, PlanarTarget, Isometry3<f64>) {
        let camera = CameraModel::new(
            400,
            300,
            520.0,
            515.0,
            201.3,
            148.7,
            Distortion::BrownConrady([-0.12, 0.05, 4e-4, -3e-4, 0.0]),
        )
        .unwrap();
        let dictionary = Dictionary::predefined("DICT_4X4_50").unwrap();
        let mut items = vec![TargetItem::Checkerboard {
            top_left: [-0.06, -0.045],
            square: 0.012,
            squares_x: 5,
            squares_y: 4,
            top_left_black: true,
        }];
        for (k, x) in [0.005, 0.035].iter().enumerate() {
            items.push(TargetItem::Marker {
                dictionary,
                id: 7 + k,
                top_left: [*x, -0.04],
                side: 0.025,
                border_bits: 1,
            });
        }
        items.push(TargetItem::Hole {
            centre: [0.02, 0.025],
            diameter: 0.006,
        });
        items.push(TargetItem::Hole {
            centre: [-0.03, 0.03],
            diameter: 0.0015,
        });
        let pose = Isometry3::new(
            Vector3::new(0.004, -0.003, 0.16),
            Vector3::new(0.35, -0.25, 0.12),
        );
        (camera, PlanarTarget { items }, pose)
    }

    /// The edge-mask path gives the image of supersampling every pixel (the path taken without
    /// a mask): a pixel it takes as flat really is flat.
    #[test]
    fn edge_mask_shading_equals_supersampling_every_pixel() {
        let (camera, target, pose) = scene();
        let geom = ViewGeometry::new(&camera, &target, &pose);
        let (s, bg) = (6, 0.5);
        let grey_of = |r: f64| if r.is_nan() { 128.0 } else { 20.0 + 210.0 * r };
        let n = (camera.width * camera.height) as usize;
        let mask = geom
            .edge_mask(&pose, Vec::new())
            .expect("the plane fills the view");
        let flat_share = mask.iter().filter(|&&m| m == 0).count() as f64 / n as f64;
        assert!(
            flat_share > 0.8,
            "the mask marks {:.0} % of the pixels as flat",
            100.0 * flat_share
        );
        let (mut fast, mut dense) = (vec![0.0; n], vec![0.0; n]);
        geom.shade(Some(&mask), s, bg, &grey_of, &mut fast);
        geom.shade(None, s, bg, &grey_of, &mut dense);
        let worst = fast
            .iter()
            .zip(&dense)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-9,
            "the edge-mask path differs from dense supersampling by up to {worst} grey levels"
        );
        // the scene has edges of every kind, so the comparison means something
        let edge_pixels = dense
            .iter()
            .filter(|g| (**g - 20.0).abs() > 1e-6 && (**g - 230.0).abs() > 1e-6)
            .count();
        assert!(edge_pixels > 2000, "{edge_pixels} mixed pixels");
    }
}
