//! Pinhole camera with Brown–Conrady lens distortion (OpenCV's `calibrateCamera` model with
//! k1, k2, p1, p2, k3).
//!
//! Frames: the camera frame has x right, y down, z forward along the optical axis (OpenCV).
//! A pose maps target (world) coordinates to camera coordinates: X_cam = R·X_target + t.
//! Distortion maps *ideal* normalised coordinates (x, y) = (X/Z, Y/Z) to *distorted* ones:
//!   x_d = x(1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2x²)
//!   y_d = y(1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2y²) + 2 p2 x y,   r² = x² + y²
//! and pixels are u = fx·x_d + cx, v = fy·y_d + cy (pixel centres at integers, see the crate doc).

use crate::error::{invalid, Result};
use nalgebra::{Isometry3, Point2, Point3};

/// Brown–Conrady distortion coefficients, OpenCV order (k1, k2, p1, p2, k3). Dimensionless.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BrownConrady {
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
    pub k3: f64,
}

impl BrownConrady {
    /// Ideal → distorted normalised coordinates.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        (
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// Distorted → ideal normalised coordinates by Newton iteration on the 2×2 Jacobian, starting
    /// from `guess` (pass the distorted point itself when there is no better guess).
    /// Returns None when it does not converge to 1e-12 (outside the model's invertible region).
    pub fn undistort_from(&self, xd: f64, yd: f64, guess: (f64, f64)) -> Option<(f64, f64)> {
        let (mut x, mut y) = guess;
        for _ in 0..30 {
            let (fx, fy) = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex.abs() < 1e-12 && ey.abs() < 1e-12 {
                return Some((x, y));
            }
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
            let drad = self.k1 + r2 * (2.0 * self.k2 + 3.0 * r2 * self.k3); // d radial / d r2
            let j11 = radial + x * drad * 2.0 * x + 2.0 * self.p1 * y + 6.0 * self.p2 * x;
            let j12 = x * drad * 2.0 * y + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
            let j21 = y * drad * 2.0 * x + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
            let j22 = radial + y * drad * 2.0 * y + 6.0 * self.p1 * y + 2.0 * self.p2 * x;
            let det = j11 * j22 - j12 * j21;
            if det.abs() < 1e-15 || !det.is_finite() {
                return None;
            }
            x -= (j22 * ex - j12 * ey) / det;
            y -= (-j21 * ex + j11 * ey) / det;
        }
        None
    }

    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        self.undistort_from(xd, yd, (xd, yd))
    }
}

/// Pinhole intrinsics (pixels) plus distortion and the image size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeCamera {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub distortion: BrownConrady,
    pub width: u32,
    pub height: u32,
}

impl PinholeCamera {
    pub fn new(fx: f64, fy: f64, cx: f64, cy: f64, width: u32, height: u32) -> Result<Self> {
        for (name, v) in [("fx", fx), ("fy", fy)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(
                    name,
                    format!("focal length must be finite and > 0, got {v}"),
                ));
            }
        }
        if !(cx.is_finite() && cy.is_finite()) {
            return Err(invalid("cx/cy", "principal point must be finite"));
        }
        if width == 0 || height == 0 {
            return Err(invalid("width/height", "image size must be non-zero"));
        }
        Ok(Self {
            fx,
            fy,
            cx,
            cy,
            distortion: BrownConrady::default(),
            width,
            height,
        })
    }

    pub fn with_distortion(mut self, d: BrownConrady) -> Self {
        self.distortion = d;
        self
    }

    /// Project a camera-frame point to pixels (with distortion). None if it is behind the camera.
    pub fn project_camera_point(&self, p: &Point3<f64>) -> Option<Point2<f64>> {
        if p.z <= 0.0 {
            return None;
        }
        let (xd, yd) = self.distortion.distort(p.x / p.z, p.y / p.z);
        Some(Point2::new(self.fx * xd + self.cx, self.fy * yd + self.cy))
    }

    /// Project a target-frame point seen with `pose` (target → camera).
    pub fn project(&self, pose: &Isometry3<f64>, p: &Point3<f64>) -> Option<Point2<f64>> {
        self.project_camera_point(&(pose * p))
    }

    /// Pixel → ideal normalised coordinates (undistorted ray direction (x, y, 1)).
    pub fn pixel_to_normalized(&self, u: f64, v: f64) -> Option<(f64, f64)> {
        let xd = (u - self.cx) / self.fx;
        let yd = (v - self.cy) / self.fy;
        self.distortion.undistort(xd, yd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undistort_inverts_distort() {
        let d = BrownConrady {
            k1: -0.28,
            k2: 0.09,
            p1: 0.001,
            p2: -0.0015,
            k3: -0.01,
        };
        for &(x, y) in &[(0.0, 0.0), (0.3, -0.2), (-0.5, 0.4), (0.6, 0.45)] {
            let (xd, yd) = d.distort(x, y);
            let (xu, yu) = d.undistort(xd, yd).unwrap();
            assert!(
                (xu - x).abs() < 1e-11 && (yu - y).abs() < 1e-11,
                "({x}, {y}) -> ({xu}, {yu})"
            );
        }
    }

    #[test]
    fn projection_uses_opencv_pixel_convention() {
        let cam = PinholeCamera::new(1000.0, 1000.0, 319.5, 239.5, 640, 480).unwrap();
        let p = cam
            .project_camera_point(&Point3::new(0.0, 0.0, 1.0))
            .unwrap();
        assert_eq!((p.x, p.y), (319.5, 239.5));
        let q = cam
            .project_camera_point(&Point3::new(0.01, -0.02, 2.0))
            .unwrap();
        assert!((q.x - 324.5).abs() < 1e-12 && (q.y - 229.5).abs() < 1e-12);
        assert!(cam
            .project_camera_point(&Point3::new(0.0, 0.0, -1.0))
            .is_none());
        assert!(PinholeCamera::new(0.0, 1.0, 0.0, 0.0, 10, 10).is_err());
    }
}
