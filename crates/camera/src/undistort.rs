//! Undistortion of points (OpenCV's `undistortPoints` algorithms, iteration for iteration) and
//! per-pixel undistortion/rectification maps (`initUndistortRectifyMap`).
//!
//! Brown–Conrady: OpenCV's fixed-point iteration x ← (x₀ − Δtangential(x)) / radial(x), starting at
//! the distorted normalised point; OpenCV's default is 5 iterations without a tolerance
//! ([`UndistortCriteria::OPENCV_PINHOLE`]), which is *not* converged for strong distortion, so the
//! default here is [`UndistortCriteria::CONVERGED`]. The tolerance, when set, is the pixel distance
//! between the re-distorted estimate and the input, checked before each iteration (as OpenCV).
//! Fisheye: Newton on θ from θ_d = r_d, OpenCV's default 10 iterations / 1e-8 rad.
//!
//! These reproduce OpenCV's results (including where its iteration stops short) for comparisons
//! with it; the exact inverse of the distortion model, for rendering and geometry, is
//! [`Distortion::undistort`] (Newton on both coordinates).

use crate::distortion::Distortion;
use crate::model::CameraModel;
use nalgebra::{Matrix3, Vector3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UndistortCriteria {
    pub max_iterations: usize,
    /// Stop tolerance (pixels for Brown–Conrady, radians of θ for fisheye); None = iterations only.
    pub epsilon: Option<f64>,
}

impl UndistortCriteria {
    /// `cv::undistortPoints` default: TermCriteria(COUNT, 5, 0.01).
    pub const OPENCV_PINHOLE: UndistortCriteria = UndistortCriteria {
        max_iterations: 5,
        epsilon: None,
    };
    /// `cv::fisheye::undistortPoints` default: TermCriteria(MAX_ITER + EPS, 10, 1e-8).
    pub const OPENCV_FISHEYE: UndistortCriteria = UndistortCriteria {
        max_iterations: 10,
        epsilon: Some(1e-8),
    };
    /// Iterate to numerical convergence.
    pub const CONVERGED: UndistortCriteria = UndistortCriteria {
        max_iterations: 200,
        epsilon: Some(1e-13),
    };
}

/// Pixel → ideal normalised coordinates (x, y) = (X/Z, Y/Z). For fisheye points that cannot be
/// inverted (θ flips sign, or no convergence with a tolerance), OpenCV returns (−1e6, −1e6); so do we.
pub fn undistort_to_normalized(
    cam: &CameraModel,
    pixel: [f64; 2],
    criteria: UndistortCriteria,
) -> [f64; 2] {
    let x0 = (pixel[0] - cam.cx) / cam.fx;
    let y0 = (pixel[1] - cam.cy) / cam.fy;
    match cam.distortion {
        Distortion::BrownConrady(k) => {
            let [k1, k2, p1, p2, k3] = k;
            let (mut x, mut y) = (x0, y0);
            let mut error = f64::MAX;
            for _ in 0..criteria.max_iterations {
                if let Some(eps) = criteria.epsilon {
                    if error < eps {
                        break;
                    }
                }
                let r2 = x * x + y * y;
                let icdist = 1.0 / (1.0 + ((k3 * r2 + k2) * r2 + k1) * r2);
                if icdist < 0.0 {
                    // OpenCV: outside the invertible region, give back the distorted point.
                    x = x0;
                    y = y0;
                    break;
                }
                let dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
                let dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
                x = (x0 - dx) * icdist;
                y = (y0 - dy) * icdist;
                if criteria.epsilon.is_some() {
                    let (xd, yd) = cam.distortion.distort(x, y);
                    let [u, v] = cam.normalized_to_pixel(xd, yd);
                    error = ((u - pixel[0]).powi(2) + (v - pixel[1]).powi(2)).sqrt();
                }
            }
            [x, y]
        }
        Distortion::Fisheye(k) => {
            let theta_d = (x0 * x0 + y0 * y0)
                .sqrt()
                .clamp(-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);
            let mut converged = false;
            let mut theta = theta_d;
            let mut scale = 0.0;
            let eps = criteria.epsilon;
            if eps.is_none() || theta_d.abs() > eps.unwrap_or(0.0) {
                for _ in 0..criteria.max_iterations {
                    let t2 = theta * theta;
                    let t4 = t2 * t2;
                    let t6 = t4 * t2;
                    let t8 = t6 * t2;
                    let fix = (theta * (1.0 + k[0] * t2 + k[1] * t4 + k[2] * t6 + k[3] * t8)
                        - theta_d)
                        / (1.0
                            + 3.0 * k[0] * t2
                            + 5.0 * k[1] * t4
                            + 7.0 * k[2] * t6
                            + 9.0 * k[3] * t8);
                    theta -= fix;
                    if let Some(e) = eps {
                        if fix.abs() < e {
                            converged = true;
                            break;
                        }
                    }
                }
                scale = theta.tan() / theta_d;
            } else {
                converged = true;
            }
            let flipped = (theta_d < 0.0 && theta > 0.0) || (theta_d > 0.0 && theta < 0.0);
            if (converged || eps.is_none()) && !flipped {
                [x0 * scale, y0 * scale]
            } else {
                [-1e6, -1e6]
            }
        }
    }
}

/// `cv::undistortPoints(src, K, D, R, P)`: undistort, rotate by `rectification` (identity if
/// None) and map through `new_camera` (3×3 left block of P; None gives normalised coordinates).
pub fn undistort_points(
    cam: &CameraModel,
    pixels: &[[f64; 2]],
    rectification: Option<&Matrix3<f64>>,
    new_camera: Option<&Matrix3<f64>>,
    criteria: UndistortCriteria,
) -> Vec<[f64; 2]> {
    let rr = new_camera.copied().unwrap_or_else(Matrix3::identity)
        * rectification.copied().unwrap_or_else(Matrix3::identity);
    pixels
        .iter()
        .map(|&p| {
            let [x, y] = undistort_to_normalized(cam, p, criteria);
            let q = rr * Vector3::new(x, y, 1.0);
            [q.x / q.z, q.y / q.z]
        })
        .collect()
}

/// Per-pixel source coordinates for remapping a distorted image to an undistorted/rectified one
/// (row-major, `map_x[v·width + u]`), single precision as OpenCV's CV_32FC1 maps.
#[derive(Debug, Clone, PartialEq)]
pub struct UndistortMap {
    pub width: u32,
    pub height: u32,
    pub map_x: Vec<f32>,
    pub map_y: Vec<f32>,
}

/// `cv::initUndistortRectifyMap` / `cv::fisheye::initUndistortRectifyMap` for the output image
/// size `(width, height)`: for each output pixel, the distorted source pixel. `new_camera`
/// defaults to the camera's own K, `rectification` to identity. Returns None if P·R is singular.
pub fn undistort_rectify_map(
    cam: &CameraModel,
    rectification: Option<&Matrix3<f64>>,
    new_camera: Option<&Matrix3<f64>>,
    size: (u32, u32),
) -> Option<UndistortMap> {
    let p = new_camera.copied().unwrap_or_else(|| cam.k_matrix());
    let r = rectification.copied().unwrap_or_else(Matrix3::identity);
    let ir = (p * r).try_inverse()?;
    let (w, h) = size;
    let mut map_x = Vec::with_capacity((w * h) as usize);
    let mut map_y = Vec::with_capacity((w * h) as usize);
    for v in 0..h {
        for u in 0..w {
            let q = ir * Vector3::new(u as f64, v as f64, 1.0);
            let (x, y) = (q.x / q.z, q.y / q.z);
            let (xd, yd) = match cam.distortion {
                Distortion::Fisheye(k) => {
                    // OpenCV's fisheye map uses scale = θ_d / r with r == 0 → 1.
                    let rr = (x * x + y * y).sqrt();
                    let theta = rr.atan();
                    let t2 = theta * theta;
                    let theta_d =
                        theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
                    let s = if rr == 0.0 { 1.0 } else { theta_d / rr };
                    (x * s, y * s)
                }
                d => d.distort(x, y),
            };
            let [pu, pv] = cam.normalized_to_pixel(xd, yd);
            map_x.push(pu as f32);
            map_y.push(pv as f32);
        }
    }
    Some(UndistortMap {
        width: w,
        height: h,
        map_x,
        map_y,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn converged_undistortion_inverts_projection() {
        for d in [
            Distortion::BrownConrady([-0.25, 0.08, 1e-3, -1e-3, -0.01]),
            Distortion::Fisheye([0.03, -0.01, 0.002, -0.0004]),
        ] {
            let cam = CameraModel::new(1600, 1200, 1100.0, 1098.0, 801.0, 597.0, d).unwrap();
            for &(x, y) in &[(0.3, -0.2), (-0.5, 0.4), (0.0, 0.0), (0.05, 0.6)] {
                let (xd, yd) = d.distort(x, y);
                let px = cam.normalized_to_pixel(xd, yd);
                let [xu, yu] = undistort_to_normalized(&cam, px, UndistortCriteria::CONVERGED);
                assert!(
                    (xu - x).abs() < 1e-10 && (yu - y).abs() < 1e-10,
                    "{d:?} ({x},{y}) → ({xu},{yu})"
                );
            }
        }
    }

    #[test]
    fn map_of_undistorted_camera_is_identity() {
        let cam = CameraModel::new(8, 6, 10.0, 10.0, 3.5, 2.5, Distortion::none()).unwrap();
        let m = undistort_rectify_map(&cam, None, None, (8, 6)).unwrap();
        assert_eq!(m.map_x[3 * 8 + 5], 5.0);
        assert_eq!(m.map_y[3 * 8 + 5], 3.0);
    }
}
