//! Lens distortion models, exactly as OpenCV evaluates them, with analytic derivatives.
//!
//! Both models map *ideal* normalised coordinates (x, y) = (X/Z, Y/Z) of a camera-frame point to
//! *distorted* normalised coordinates (x_d, y_d); pixels follow as u = fx·x_d + cx, v = fy·y_d + cy.
//!
//! * [`Distortion::BrownConrady`] — OpenCV `calibrateCamera` / ROS "plumb_bob", coefficient order
//!   (k1, k2, p1, p2, k3):
//!   x_d = x(1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2x²)
//!   y_d = y(1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2y²) + 2 p2 x y,   r² = x² + y².
//! * [`Distortion::Fisheye`] — OpenCV `cv::fisheye` (Kannala–Brandt) / ROS "equidistant", order
//!   (k1, k2, k3, k4): θ = atan(r), θ_d = θ(1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸),
//!   (x_d, y_d) = (θ_d / r)·(x, y) for r > 1e-8, else (x, y) (OpenCV's threshold).

use nalgebra::{DMatrix, Matrix2};

/// A lens distortion model with its coefficients (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distortion {
    /// (k1, k2, p1, p2, k3), OpenCV order.
    BrownConrady([f64; 5]),
    /// (k1, k2, k3, k4), OpenCV fisheye order.
    Fisheye([f64; 4]),
}

/// Distorted coordinates together with their derivatives.
#[derive(Debug, Clone, PartialEq)]
pub struct DistortionEval {
    pub xd: f64,
    pub yd: f64,
    /// ∂(x_d, y_d)/∂(x, y).
    pub d_point: Matrix2<f64>,
    /// ∂(x_d, y_d)/∂(coefficients), 2 × n_coefficients, columns in the model's coefficient order.
    pub d_coeffs: DMatrix<f64>,
}

/// OpenCV's radius below which the fisheye model is treated as the identity.
const FISHEYE_SMALL_R: f64 = 1e-8;

impl Distortion {
    /// No distortion, Brown–Conrady flavour.
    pub fn none() -> Self {
        Distortion::BrownConrady([0.0; 5])
    }

    pub fn coefficients(&self) -> Vec<f64> {
        match self {
            Distortion::BrownConrady(k) => k.to_vec(),
            Distortion::Fisheye(k) => k.to_vec(),
        }
    }

    pub fn n_coefficients(&self) -> usize {
        match self {
            Distortion::BrownConrady(_) => 5,
            Distortion::Fisheye(_) => 4,
        }
    }

    /// Same model with new coefficients; None unless `c.len() == n_coefficients()`.
    pub fn with_coefficients(&self, c: &[f64]) -> Option<Self> {
        (c.len() == self.n_coefficients()).then(|| self.with_coefficients_unchecked(c))
    }

    /// Solver-internal: `c` holds at least `n_coefficients()` values (extra ignored).
    pub(crate) fn with_coefficients_unchecked(&self, c: &[f64]) -> Self {
        match self {
            Distortion::BrownConrady(_) => Distortion::BrownConrady([c[0], c[1], c[2], c[3], c[4]]),
            Distortion::Fisheye(_) => Distortion::Fisheye([c[0], c[1], c[2], c[3]]),
        }
    }

    /// The ROS `distortion_model` string: "plumb_bob" or "equidistant".
    pub fn ros_name(&self) -> &'static str {
        match self {
            Distortion::BrownConrady(_) => "plumb_bob",
            Distortion::Fisheye(_) => "equidistant",
        }
    }

    /// Ideal → distorted normalised coordinates.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        match self {
            Distortion::BrownConrady(k) => {
                let [k1, k2, p1, p2, k3] = *k;
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                (
                    x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                    y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
                )
            }
            Distortion::Fisheye(k) => {
                let r = (x * x + y * y).sqrt();
                let theta = r.atan();
                let t2 = theta * theta;
                let theta_d = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
                let cdist = if r > FISHEYE_SMALL_R {
                    theta_d / r
                } else {
                    1.0
                };
                (x * cdist, y * cdist)
            }
        }
    }

    /// Distorted → ideal normalised coordinates by Newton iteration to 1e-12 (exact inverse of
    /// [`Self::distort`], unlike OpenCV's fixed-iteration `undistortPoints`). None when it does not
    /// converge (outside the model's invertible region). No allocation: used per pixel by renderers.
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        match self {
            Distortion::BrownConrady(k) => {
                let [k1, k2, p1, p2, k3] = *k;
                let (mut x, mut y) = (xd, yd);
                for _ in 0..30 {
                    let r2 = x * x + y * y;
                    let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                    let ex = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
                    let ey = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
                    if ex.abs() < 1e-12 && ey.abs() < 1e-12 {
                        return Some((x, y));
                    }
                    let drad = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3); // d radial / d r²
                    let j11 = radial + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x;
                    let j12 = 2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y;
                    let j22 = radial + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x;
                    let det = j11 * j22 - j12 * j12;
                    if !(det.abs() > 1e-15 && det.is_finite()) {
                        return None;
                    }
                    x -= (j22 * ex - j12 * ey) / det;
                    y -= (-j12 * ex + j11 * ey) / det;
                }
                None
            }
            Distortion::Fisheye(k) => {
                // Radial model: solve θ(1 + k1θ² + …) = r_d for θ ∈ [0, π/2), then r = tan θ.
                let rd = (xd * xd + yd * yd).sqrt();
                if rd <= FISHEYE_SMALL_R {
                    return Some((xd, yd));
                }
                let mut theta = rd.min(1.5);
                for _ in 0..50 {
                    let t2 = theta * theta;
                    let f =
                        theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - rd;
                    if f.abs() < 1e-13 {
                        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&theta) {
                            return None;
                        }
                        let s = theta.tan() / rd;
                        return Some((xd * s, yd * s));
                    }
                    let df = 1.0
                        + t2 * (3.0 * k[0]
                            + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
                    if !(df.abs() > 1e-15) {
                        return None;
                    }
                    theta -= f / df;
                }
                None
            }
        }
    }

    /// Ideal → distorted with analytic derivatives.
    pub fn distort_with_jacobians(&self, x: f64, y: f64) -> DistortionEval {
        match self {
            Distortion::BrownConrady(k) => {
                let [k1, k2, p1, p2, k3] = *k;
                let r2 = x * x + y * y;
                let r4 = r2 * r2;
                let r6 = r4 * r2;
                let radial = 1.0 + k1 * r2 + k2 * r4 + k3 * r6;
                let drad = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r4; // d radial / d r²
                let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
                let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
                let d_point = Matrix2::new(
                    radial + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x,
                    2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y,
                    2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y,
                    radial + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x,
                );
                let d_coeffs = DMatrix::from_row_slice(
                    2,
                    5,
                    &[
                        x * r2,
                        x * r4,
                        2.0 * x * y,
                        r2 + 2.0 * x * x,
                        x * r6, //
                        y * r2,
                        y * r4,
                        r2 + 2.0 * y * y,
                        2.0 * x * y,
                        y * r6,
                    ],
                );
                DistortionEval {
                    xd,
                    yd,
                    d_point,
                    d_coeffs,
                }
            }
            Distortion::Fisheye(k) => {
                let r = (x * x + y * y).sqrt();
                let theta = r.atan();
                let t2 = theta * theta;
                let poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
                let theta_d = theta * poly;
                if r <= FISHEYE_SMALL_R {
                    // Identity branch (OpenCV): derivative of θ_d/r → 1 at r = 0, coefficients act as r³.
                    return DistortionEval {
                        xd: x,
                        yd: y,
                        d_point: Matrix2::identity(),
                        d_coeffs: DMatrix::zeros(2, 4),
                    };
                }
                let scale = theta_d / r;
                // d θ_d / d θ and d θ / d r
                let dthd_dth = 1.0
                    + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
                let dth_dr = 1.0 / (1.0 + r * r);
                let dscale_dr = (dthd_dth * dth_dr * r - theta_d) / (r * r);
                let (ux, uy) = (x / r, y / r);
                let d_point = Matrix2::new(
                    scale + x * dscale_dr * ux,
                    x * dscale_dr * uy,
                    y * dscale_dr * ux,
                    scale + y * dscale_dr * uy,
                );
                let mut d_coeffs = DMatrix::zeros(2, 4);
                let mut tp = theta * t2; // θ³, θ⁵, θ⁷, θ⁹
                for i in 0..4 {
                    d_coeffs[(0, i)] = x / r * tp;
                    d_coeffs[(1, i)] = y / r * tp;
                    tp *= t2;
                }
                DistortionEval {
                    xd: x * scale,
                    yd: y * scale,
                    d_point,
                    d_coeffs,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newton_undistort_inverts_distort() {
        for d in [
            Distortion::BrownConrady([-0.28, 0.09, 0.001, -0.0015, -0.01]),
            Distortion::Fisheye([0.02, -0.01, 0.004, -0.001]),
        ] {
            for &(x, y) in &[(0.0, 0.0), (0.3, -0.2), (-0.5, 0.4), (0.6, 0.45)] {
                let (xd, yd) = d.distort(x, y);
                let (xu, yu) = d.undistort(xd, yd).unwrap();
                assert!(
                    (xu - x).abs() < 1e-11 && (yu - y).abs() < 1e-11,
                    "{d:?}: ({x}, {y}) -> ({xu}, {yu})"
                );
            }
        }
    }

    fn check_jacobians(d: Distortion, x: f64, y: f64) {
        let e = d.distort_with_jacobians(x, y);
        let (xd, yd) = d.distort(x, y);
        assert!((e.xd - xd).abs() < 1e-15 && (e.yd - yd).abs() < 1e-15);
        let h = 1e-7;
        for (j, (dx, dy)) in [(h, 0.0), (0.0, h)].iter().enumerate() {
            let (a, b) = d.distort(x + dx, y + dy);
            let (a0, b0) = d.distort(x - dx, y - dy);
            assert!(
                ((a - a0) / (2.0 * h) - e.d_point[(0, j)]).abs() < 1e-7,
                "{d:?} d_point col {j}"
            );
            assert!(
                ((b - b0) / (2.0 * h) - e.d_point[(1, j)]).abs() < 1e-7,
                "{d:?} d_point col {j}"
            );
        }
        let c = d.coefficients();
        for i in 0..c.len() {
            let mut cp = c.clone();
            cp[i] += h;
            let mut cm = c.clone();
            cm[i] -= h;
            let (a, b) = d.with_coefficients(&cp).unwrap().distort(x, y);
            let (a0, b0) = d.with_coefficients(&cm).unwrap().distort(x, y);
            assert!(
                ((a - a0) / (2.0 * h) - e.d_coeffs[(0, i)]).abs() < 1e-7,
                "{d:?} coeff {i}"
            );
            assert!(
                ((b - b0) / (2.0 * h) - e.d_coeffs[(1, i)]).abs() < 1e-7,
                "{d:?} coeff {i}"
            );
        }
    }

    #[test]
    fn analytic_jacobians_match_central_differences() {
        let bc = Distortion::BrownConrady([-0.28, 0.09, 1e-3, -5e-4, -0.01]);
        let fe = Distortion::Fisheye([0.05, -0.01, 0.003, -0.0005]);
        for &(x, y) in &[(0.3, -0.2), (-0.6, 0.45), (0.01, 0.02), (1.2, 0.7)] {
            check_jacobians(bc, x, y);
            check_jacobians(fe, x, y);
        }
    }

    #[test]
    fn brown_conrady_formula_by_hand() {
        // x=0.5, y=-0.25: r²=0.3125; radial = 1 + 0.1·0.3125 + 0.01·0.09765625 + 0.001·0.030517578125
        let d = Distortion::BrownConrady([0.1, 0.01, 0.002, 0.003, 0.001]);
        let (xd, yd) = d.distort(0.5, -0.25);
        let radial = 1.0 + 0.1 * 0.3125 + 0.01 * 0.09765625 + 0.001 * 0.030517578125;
        let ex = 0.5 * radial + 2.0 * 0.002 * 0.5 * -0.25 + 0.003 * (0.3125 + 0.5);
        let ey = -0.25 * radial + 0.002 * (0.3125 + 0.125) + 2.0 * 0.003 * 0.5 * -0.25;
        assert!((xd - ex).abs() < 1e-15 && (yd - ey).abs() < 1e-15);
    }
}
