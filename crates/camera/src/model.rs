//! Camera model: pinhole intrinsics plus a lens distortion model, with projection Jacobians.
//!
//! Pixel convention (as OpenCV): the centre of the top-left pixel is (0, 0), u to the right, v down.
//! Intrinsics in pixels: u = fx·x_d + cx, v = fy·y_d + cy (no skew). The flat intrinsic parameter
//! vector used by calibration and covariances is (fx, fy, cx, cy, distortion coefficients…).

use crate::distortion::Distortion;
use crate::error::{invalid, CameraError, Result};
use crate::pose::{skew, Pose};
use nalgebra::{DMatrix, Matrix2x3, Matrix3, SMatrix, Vector3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraModel {
    /// Image size in pixels.
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub distortion: Distortion,
}

/// A projected pixel with derivatives with respect to everything it depends on.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    pub u: f64,
    pub v: f64,
    /// ∂(u,v)/∂(fx, fy, cx, cy).
    pub d_intrinsics: SMatrix<f64, 2, 4>,
    /// ∂(u,v)/∂(distortion coefficients), model order.
    pub d_distortion: DMatrix<f64>,
    /// ∂(u,v)/∂(δx, δy, δz, δθx, δθy, δθz), the perturbation convention of [`crate::pose`].
    pub d_pose: SMatrix<f64, 2, 6>,
    /// ∂(u,v)/∂(target point X, Y, Z).
    pub d_point: Matrix2x3<f64>,
}

impl CameraModel {
    /// Checked constructor: positive finite focal lengths, non-zero image size.
    pub fn new(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        distortion: Distortion,
    ) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(invalid(
                "image_size",
                format!("{width}×{height} must be non-zero"),
            ));
        }
        for (n, v) in [("fx", fx), ("fy", fy)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(n, format!("{v} must be positive and finite")));
            }
        }
        for (n, v) in [("cx", cx), ("cy", cy)] {
            if !v.is_finite() {
                return Err(invalid(n, format!("{v} must be finite")));
            }
        }
        if distortion.coefficients().iter().any(|c| !c.is_finite()) {
            return Err(invalid("distortion", "coefficients must be finite"));
        }
        Ok(CameraModel {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
            distortion,
        })
    }

    /// K as a 3×3 matrix.
    pub fn k_matrix(&self) -> Matrix3<f64> {
        Matrix3::new(self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0)
    }

    /// (fx, fy, cx, cy, coefficients…).
    pub fn params(&self) -> Vec<f64> {
        let mut p = vec![self.fx, self.fy, self.cx, self.cy];
        p.extend(self.distortion.coefficients());
        p
    }

    pub fn n_params(&self) -> usize {
        4 + self.distortion.n_coefficients()
    }

    /// Same model with parameters taken from `p` (layout of [`Self::params`]); errors on a wrong
    /// length or non-finite values.
    pub fn with_params(&self, p: &[f64]) -> Result<Self> {
        if p.len() != self.n_params() {
            return Err(invalid(
                "params",
                format!(
                    "expected {} values (fx, fy, cx, cy, coefficients), got {}",
                    self.n_params(),
                    p.len()
                ),
            ));
        }
        if p.iter().any(|v| !v.is_finite()) {
            return Err(invalid("params", "non-finite value"));
        }
        Ok(self.with_params_unchecked(p))
    }

    /// [`Self::with_params`] without checks, for the solvers (length guaranteed by construction).
    pub(crate) fn with_params_unchecked(&self, p: &[f64]) -> Self {
        CameraModel {
            fx: p[0],
            fy: p[1],
            cx: p[2],
            cy: p[3],
            distortion: self.distortion.with_coefficients_unchecked(&p[4..]),
            ..*self
        }
    }

    /// Distorted normalised coordinates → pixel.
    pub fn normalized_to_pixel(&self, xd: f64, yd: f64) -> [f64; 2] {
        [self.fx * xd + self.cx, self.fy * yd + self.cy]
    }

    /// Pixel → ideal normalised coordinates (x, y) = (X/Z, Y/Z) of the viewing ray, by the exact
    /// (Newton) inverse of the distortion; None outside the model's invertible region.
    pub fn pixel_to_normalized(&self, u: f64, v: f64) -> Option<[f64; 2]> {
        let (x, y) = self
            .distortion
            .undistort((u - self.cx) / self.fx, (v - self.cy) / self.fy)?;
        Some([x, y])
    }

    /// Projects a camera-frame point; errors if it is not in front of the camera (z ≤ 0).
    pub fn project_camera_point(&self, p: &Vector3<f64>) -> Result<[f64; 2]> {
        if !(p.z > 0.0) {
            return Err(CameraError::Degenerate {
                what: "projection".into(),
                reason: format!("point {p:?} has z ≤ 0"),
            });
        }
        let (xd, yd) = self.distortion.distort(p.x / p.z, p.y / p.z);
        Ok(self.normalized_to_pixel(xd, yd))
    }

    /// Projects a target point seen at `pose`.
    pub fn project(&self, pose: &Pose, x: &Vector3<f64>) -> Result<[f64; 2]> {
        self.project_camera_point(&pose.transform(x))
    }

    /// Projection with all Jacobians (analytic).
    pub fn project_with_jacobians(&self, pose: &Pose, x: &Vector3<f64>) -> Result<Projection> {
        let pc = pose.transform(x);
        if !(pc.z > 0.0) {
            return Err(CameraError::Degenerate {
                what: "projection".into(),
                reason: format!("point {x:?} is behind the camera (z = {})", pc.z),
            });
        }
        let iz = 1.0 / pc.z;
        let (xn, yn) = (pc.x * iz, pc.y * iz);
        let e = self.distortion.distort_with_jacobians(xn, yn);
        let u = self.fx * e.xd + self.cx;
        let v = self.fy * e.yd + self.cy;
        let d_intrinsics = SMatrix::<f64, 2, 4>::new(e.xd, 0.0, 1.0, 0.0, 0.0, e.yd, 0.0, 1.0);
        let mut d_distortion = e.d_coeffs.clone();
        d_distortion.row_mut(0).scale_mut(self.fx);
        d_distortion.row_mut(1).scale_mut(self.fy);
        // ∂(u,v)/∂(x_d,y_d) · ∂(x_d,y_d)/∂(x,y) · ∂(x,y)/∂X_cam
        let f = nalgebra::Matrix2::new(self.fx, 0.0, 0.0, self.fy);
        let dn_dpc = Matrix2x3::new(iz, 0.0, -pc.x * iz * iz, 0.0, iz, -pc.y * iz * iz);
        let d_pc = f * e.d_point * dn_dpc;
        let rx = pose.rotation * x;
        let mut d_pose = SMatrix::<f64, 2, 6>::zeros();
        d_pose.fixed_view_mut::<2, 3>(0, 0).copy_from(&d_pc);
        d_pose
            .fixed_view_mut::<2, 3>(0, 3)
            .copy_from(&(d_pc * (-skew(&rx))));
        let d_point = d_pc * pose.rotation.matrix();
        Ok(Projection {
            u,
            v,
            d_intrinsics,
            d_distortion,
            d_pose,
            d_point,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_jacobians_match_central_differences() {
        for dist in [
            Distortion::BrownConrady([-0.2, 0.05, 1e-3, -2e-3, 0.01]),
            Distortion::Fisheye([0.02, -0.01, 0.004, -0.001]),
        ] {
            let cam = CameraModel::new(1280, 960, 900.0, 905.0, 641.0, 479.0, dist).unwrap();
            let pose = Pose::from_rvec_tvec([0.3, -0.2, 0.1], [-0.05, 0.03, 0.6]);
            let x = Vector3::new(0.08, -0.05, 0.0);
            let pr = cam.project_with_jacobians(&pose, &x).unwrap();
            let h = 1e-6;
            let p0 = cam.params();
            for i in 0..p0.len() {
                let (mut a, mut b) = (p0.clone(), p0.clone());
                a[i] += h;
                b[i] -= h;
                let ua = cam.with_params(&a).unwrap().project(&pose, &x).unwrap();
                let ub = cam.with_params(&b).unwrap().project(&pose, &x).unwrap();
                let an = if i < 4 {
                    pr.d_intrinsics.column(i).into_owned()
                } else {
                    pr.d_distortion
                        .column(i - 4)
                        .into_owned()
                        .fixed_rows::<2>(0)
                        .into_owned()
                };
                for r in 0..2 {
                    let num = (ua[r] - ub[r]) / (2.0 * h);
                    assert!(
                        (num - an[r]).abs() < 1e-4 * (1.0 + an[r].abs()),
                        "param {i} row {r}: {num} vs {}",
                        an[r]
                    );
                }
            }
            for j in 0..6 {
                let mut d = [0.0; 6];
                d[j] = h;
                let ua = cam.project(&pose.perturbed(&d), &x).unwrap();
                d[j] = -h;
                let ub = cam.project(&pose.perturbed(&d), &x).unwrap();
                for r in 0..2 {
                    let num = (ua[r] - ub[r]) / (2.0 * h);
                    assert!(
                        (num - pr.d_pose[(r, j)]).abs() < 1e-4 * (1.0 + num.abs()),
                        "pose {j}"
                    );
                }
            }
            for j in 0..3 {
                let mut xa = x;
                xa[j] += h;
                let mut xb = x;
                xb[j] -= h;
                let ua = cam.project(&pose, &xa).unwrap();
                let ub = cam.project(&pose, &xb).unwrap();
                for r in 0..2 {
                    let num = (ua[r] - ub[r]) / (2.0 * h);
                    assert!(
                        (num - pr.d_point[(r, j)]).abs() < 1e-4 * (1.0 + num.abs()),
                        "point {j}"
                    );
                }
            }
        }
    }
}
