//! A calibration made at one resolution used at another of the same sensor mode (seed 002
//! calibrates at 1280 × 720 and measures at 3840 × 2160): the image is the same field of view
//! sampled s times finer, so focal lengths scale by s and a pixel coordinate u becomes
//! s·(u + ½) − ½ — the ½ because the centre of the top-left pixel is (0, 0) (this crate's
//! convention, OpenCV's). Distortion acts on normalised coordinates and does not change.
//!
//! Seed 002's T4 scales a corner (640, 360) by 3 to (1920, 1080): true for coordinates measured
//! from the image's corner; in OpenCV pixel coordinates the same point is (639.5, 359.5) →
//! (1919.5, 1079.5), and a plain ×3 of OpenCV coordinates would be off by one pixel.
//!
//! A different aspect ratio is not a rescale (the sensor mode crops or bins differently): that
//! is refused, with the advice to calibrate at the resolution used.

use crate::error::{invalid, Result};
use crate::model::CameraModel;

/// The scale factors (s_u, s_v) from `from` (width, height) to `to`; refused when they differ.
pub fn resolution_scale(from: (u32, u32), to: (u32, u32)) -> Result<f64> {
    if from.0 == 0 || from.1 == 0 || to.0 == 0 || to.1 == 0 {
        return Err(invalid(
            "resolution",
            format!("{from:?} → {to:?}: a size is zero"),
        ));
    }
    let su = to.0 as f64 / from.0 as f64;
    let sv = to.1 as f64 / from.1 as f64;
    if (su - sv).abs() > 1e-9 * su {
        return Err(invalid(
            "resolution",
            format!(
                "{}×{} → {}×{} scales u by {su} and v by {sv}: not the same field of view; \
                 calibrate the camera at {}×{}",
                from.0, from.1, to.0, to.1, to.0, to.1
            ),
        ));
    }
    Ok(su)
}

/// A pixel (this crate's convention) of an image `from` (width, height) at resolution `to`.
pub fn rescale_pixel(u: f64, v: f64, from: (u32, u32), to: (u32, u32)) -> Result<(f64, f64)> {
    let s = resolution_scale(from, to)?;
    Ok((s * (u + 0.5) - 0.5, s * (v + 0.5) - 0.5))
}

impl CameraModel {
    /// The same camera at `width` × `height` (same field of view, see the module comment).
    pub fn at_resolution(&self, width: u32, height: u32) -> Result<CameraModel> {
        let s = resolution_scale((self.width, self.height), (width, height))?;
        Ok(CameraModel {
            width,
            height,
            fx: self.fx * s,
            fy: self.fy * s,
            cx: s * (self.cx + 0.5) - 0.5,
            cy: s * (self.cy + 0.5) - 0.5,
            distortion: self.distortion,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t4_corner_rescale_in_corner_and_centre_coordinates() {
        let (from, to) = ((1280, 720), (3840, 2160));
        assert_eq!(resolution_scale(from, to).unwrap(), 3.0);
        // the digest's (640, 360) → (1920, 1080) is in coordinates from the image's corner,
        // which are OpenCV's + ½
        let (u, v) = rescale_pixel(640.0 - 0.5, 360.0 - 0.5, from, to).unwrap();
        assert_eq!((u + 0.5, v + 0.5), (1920.0, 1080.0));
        // the centre pixel of the small image lands on the centre of the large one
        let (u, v) = rescale_pixel(639.5, 359.5, from, to).unwrap();
        assert_eq!((u, v), (1919.5, 1079.5));
        assert_eq!(rescale_pixel(0.0, 0.0, from, to).unwrap(), (1.0, 1.0));
    }

    #[test]
    fn a_different_aspect_ratio_is_refused_with_advice() {
        let e = resolution_scale((1280, 720), (1280, 1024))
            .unwrap_err()
            .to_string();
        assert!(e.contains("calibrate the camera at 1280×1024"), "{e}");
    }
}
