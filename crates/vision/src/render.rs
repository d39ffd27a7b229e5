//! Digital-twin renderer: planar targets (ArUco markers, checkerboards, drilled holes) seen by a pinhole camera
//! with Brown–Conrady distortion, with the exact ground-truth pixel positions of their corners.
//!
//! Target frame: the target is the plane z = 0, x to the right, y down as printed (so a front view
//! with the identity rotation shows it upright). Lengths in metres. The pose maps target → camera.
//!
//! Image formation: each pixel integrates the target's reflectance over its unit square (box
//! filter, the pixel convention of the crate doc). Pixels whose four corners and centre see the
//! same reflectance are flat; the others are supersampled on an s×s grid. Then optional Gaussian
//! blur (optics), a multiplicative lighting gradient, additive Gaussian noise, and rounding to u8.

use crate::aruco::Dictionary;
use crate::camera::{pixel_to_normalized, project, CameraModel};
use crate::error::{invalid, Result};
use image::GrayImage;
use nalgebra::{Isometry3, Point2, Point3, Vector3};
use rand::{Rng, SeedableRng};

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
    /// is black.
    Checkerboard {
        top_left: [f64; 2],
        square: f64,
        squares_x: u32,
        squares_y: u32,
    },
    /// A drilled through-hole of `diameter` (m) centred at `centre` (m), seen against an
    /// inverse-contrast backing (seed 000): it shows the opposite of what lies beneath it
    /// (black under a white square, white under a black one).
    Hole { centre: [f64; 2], diameter: f64 },
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
                let (c, r) = (u as u32, v as u32);
                let inner = |k: u32| k >= *border_bits && k < cells - border_bits;
                if inner(r) && inner(c) {
                    let n = dictionary.marker_size as u32;
                    let code = dictionary.code(*id).ok()?;
                    let bit = n * n - 1 - ((r - border_bits) * n + (c - border_bits));
                    Some(((code >> bit) & 1) as f64)
                } else {
                    Some(0.0)
                }
            }
            TargetItem::Checkerboard {
                top_left,
                square,
                squares_x,
                squares_y,
            } => {
                let u = (x - top_left[0]) / square;
                let v = (y - top_left[1]) / square;
                if !(0.0..*squares_x as f64).contains(&u) || !(0.0..*squares_y as f64).contains(&v)
                {
                    return None;
                }
                Some(if (u as u32 + v as u32) % 2 == 0 {
                    0.0
                } else {
                    1.0
                })
            }
            // Depends on what is beneath: resolved by PlanarTarget::reflectance.
            TargetItem::Hole { .. } => None,
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
            TargetItem::Hole { centre, diameter } => {
                if !(diameter.is_finite() && *diameter > 0.0) {
                    return Err(invalid("Hole.diameter", format!("must be > 0, got {diameter}")));
                }
                if !(centre[0].is_finite() && centre[1].is_finite()) {
                    return Err(invalid("Hole.centre", "must be finite"));
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

impl ViewGeometry<'_> {
    fn sample(&self, u: f64, v: f64) -> f64 {
        let Some((x, y)) = pixel_to_normalized(self.camera, u, v) else {
            return f64::NAN;
        };
        let dir = self.rot_t * Vector3::new(x, y, 1.0);
        if dir.z.abs() < 1e-15 {
            return f64::NAN;
        }
        let lambda = -self.origin.z / dir.z;
        if lambda <= 0.0 {
            return f64::NAN;
        }
        let p = self.origin + lambda * dir;
        self.target.reflectance(p.x, p.y)
    }
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
    let rot_t = pose.rotation.to_rotation_matrix().matrix().transpose();
    let geom = ViewGeometry {
        camera,
        target,
        origin: -(rot_t * pose.translation.vector),
        rot_t,
    };
    // Reflectance at pixel corners (u − 0.5, v − 0.5).
    let mut corner = vec![0.0f64; (w + 1) * (h + 1)];
    for j in 0..=h {
        for i in 0..=w {
            corner[j * (w + 1) + i] = geom.sample(i as f64 - 0.5, j as f64 - 0.5);
        }
    }
    let s = settings.supersampling as usize;
    let mut refl = vec![0.0f64; w * h];
    for j in 0..h {
        for i in 0..w {
            let c = [
                corner[j * (w + 1) + i],
                corner[j * (w + 1) + i + 1],
                corner[(j + 1) * (w + 1) + i],
                corner[(j + 1) * (w + 1) + i + 1],
                geom.sample(i as f64, j as f64),
            ];
            let uniform = c
                .iter()
                .all(|&x| x == c[0] || (x.is_nan() && c[0].is_nan()));
            let value = if uniform {
                c[0]
            } else {
                let mut acc = 0.0;
                let mut n_nan = 0usize;
                for b in 0..s {
                    for a in 0..s {
                        let u = i as f64 - 0.5 + (a as f64 + 0.5) / s as f64;
                        let v = j as f64 - 0.5 + (b as f64 + 0.5) / s as f64;
                        let r = geom.sample(u, v);
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
                    // Unseen samples show the background level, expressed as a reflectance.
                    let bg = (settings.background - settings.black_level)
                        / (settings.white_level - settings.black_level);
                    (acc + n_nan as f64 * bg) / (s * s) as f64
                }
            };
            refl[j * w + i] = value;
        }
    }
    // Convert to grey levels before blurring so unseen regions blur like anything else.
    let span = settings.white_level - settings.black_level;
    let mut grey: Vec<f64> = refl
        .iter()
        .map(|&r| {
            if r.is_nan() {
                settings.background
            } else {
                settings.black_level + span * r
            }
        })
        .collect();
    if settings.blur_sigma_px > 0.0 {
        grey = crate::filters::gaussian_blur_f64(&grey, w, h, settings.blur_sigma_px);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(settings.seed);
    let mut img = GrayImage::new(camera.width, camera.height);
    for j in 0..h {
        for i in 0..w {
            let illum = 1.0
                + settings.gradient[0] * (i as f64 - w as f64 / 2.0) / w as f64
                + settings.gradient[1] * (j as f64 - h as f64 / 2.0) / h as f64;
            let mut g = grey[j * w + i] * illum;
            if settings.noise_sigma > 0.0 {
                g += settings.noise_sigma * standard_normal(&mut rng);
            }
            img.put_pixel(
                i as u32,
                j as u32,
                image::Luma([g.round().clamp(0.0, 255.0) as u8]),
            );
        }
    }
    // Ground truth.
    let mut markers = Vec::new();
    let mut checkerboard_corners = Vec::new();
    let project = |x: f64, y: f64| -> Result<Point2<f64>> {
        project(camera, pose, &Point3::new(x, y, 0.0))
            .ok_or_else(|| crate::error::VisionError::NoSolution {
                what: "render ground truth",
                reason: format!("target point ({x}, {y}) is behind the camera"),
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
            } => {
                let mut pts = Vec::new();
                for r in 1..*squares_y {
                    for c in 1..*squares_x {
                        pts.push(project(x + c as f64 * square, y + r as f64 * square)?);
                    }
                }
                checkerboard_corners.push(pts);
            }
            TargetItem::Hole { .. } => {}
        }
    }
    Ok(RenderedView {
        image: img,
        markers,
        checkerboard_corners,
    })
}

/// Box–Muller standard normal deviate.
fn standard_normal<R: Rng>(rng: &mut R) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
