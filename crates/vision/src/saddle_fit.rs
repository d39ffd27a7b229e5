//! Sub-pixel checkerboard corners: fit two crossing blurred step edges to the pixels around a
//! saddle point.
//!
//! Model for pixel centre p, with s_i = n_i·(p − c), n_i = (cos θ_i, sin θ_i), A = Φ(s_1/σ),
//! B = Φ(s_2/σ):  I(p) = a + b·(A + B − 2AB)  (bright where exactly one side is positive).
//! Both edges pass through the corner c, so c is their intersection; the model is symmetric
//! about each line, hence unbiased for pixel integration and symmetric blur. Solved by
//! Levenberg–Marquardt (metrocell_solver); covariance s²(JᵀJ)⁻¹.

use crate::edge_fit::normal_cdf_pdf;
use image::GrayImage;
use metrocell_solver::{solve, NotEvaluable, Options, Problem, Solution};
use nalgebra::{DMatrix, Matrix2, Point2};

/// ln of the smallest edge spread the fit allows (px): a pixel integrates the image over its
/// area, which spreads a perfectly sharp edge like a 1-px box along its normal, whatever the
/// edge's angle (σ = 1/√12 ≈ 0.29 px); below that the model's point samples of a blurred step
/// no longer describe a pixel. Let lower, a sharp edge along a pixel row leaves one column of
/// intermediate pixels, which any σ ≪ 1 fits with the edge anywhere inside it: the fit wandered
/// (0.16 px off) and its covariance was singular ("did not converge").
const MIN_LN_SIGMA: f64 = -1.2425; // ln(1/√12) − 0.001

/// A refined checkerboard corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaddleCorner {
    pub position: Point2<f64>,
    /// Covariance of the position (px²).
    pub covariance: Matrix2<f64>,
    /// Edge normal angles (rad), blur σ (px), residual RMS (grey levels).
    pub theta: [f64; 2],
    pub blur_sigma: f64,
    pub residual_rms: f64,
}

/// Refine a corner near `guess` whose two edges run along directions `dir1`, `dir2` (any sign),
/// using pixels within `radius` px of the guess. None if the fit fails or wanders off.
pub fn refine_saddle(
    img: &GrayImage,
    guess: Point2<f64>,
    dir1: [f64; 2],
    dir2: [f64; 2],
    radius: f64,
) -> Option<SaddleCorner> {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let r = radius.max(2.0);
    let mut samples = Vec::new();
    for y in (guess.y - r).floor() as i64..=(guess.y + r).ceil() as i64 {
        for x in (guess.x - r).floor() as i64..=(guess.x + r).ceil() as i64 {
            if x < 0 || y < 0 || x >= w || y >= h {
                continue;
            }
            let (dx, dy) = (x as f64 - guess.x, y as f64 - guess.y);
            if dx * dx + dy * dy <= r * r {
                samples.push([
                    x as f64,
                    y as f64,
                    img.get_pixel(x as u32, y as u32)[0] as f64,
                ]);
            }
        }
    }
    if samples.len() < 20 {
        return None;
    }
    // Edge along direction d has normal (−d.y, d.x).
    let th1 = dir1[0].atan2(-dir1[1]);
    let th2 = dir2[0].atan2(-dir2[1]);
    let vals: Vec<f64> = samples.iter().map(|s| s[2]).collect();
    let lo = vals.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = vals.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    // x = (cx, cy, θ1, θ2, a, b, ln σ); try both contrast signs, keep the better fit.
    let problem = Saddle { samples: &samples };
    // Blur between a pixel's own spread (MIN_LN_SIGMA) and e^2.5 px: outside, σ stops being
    // observable.
    let (inf, ninf) = (f64::INFINITY, f64::NEG_INFINITY);
    let options = Options {
        bounds: Some((
            vec![ninf, ninf, ninf, ninf, ninf, ninf, MIN_LN_SIGMA],
            vec![inf, inf, inf, inf, inf, inf, 2.5],
        )),
        max_iterations: 60,
        // Converged when a step changes the cost by < 1e-9 of itself: parameters then move by
        // well under 1 % of their standard uncertainty.
        ftol: 1e-9,
        xtol: 1e-8,
        gtol: 1e-10,
        ..Options::default()
    };
    let mut best: Option<Solution> = None;
    for (a0, b0) in [(lo, hi - lo), (hi, lo - hi)] {
        let x0 = [
            guess.x,
            guess.y,
            th1,
            th2,
            a0,
            b0,
            0.8f64.ln().max(MIN_LN_SIGMA),
        ];
        if let Ok(fit) = solve(&problem, &x0, &options) {
            if best.as_ref().map_or(true, |b| fit.cost < b.cost) {
                best = Some(fit);
            }
        }
    }
    let fit = best?;
    let x = &fit.x;
    let c = Point2::new(x[0], x[1]);
    if (c - guess).norm() > 0.5 * r || !x.iter().all(|v| v.is_finite()) {
        return None;
    }
    let cov = fit.covariance()?;
    Some(SaddleCorner {
        position: c,
        covariance: Matrix2::new(cov[(0, 0)], cov[(0, 1)], cov[(1, 0)], cov[(1, 1)]),
        theta: [x[2], x[3]],
        blur_sigma: x[6].exp(),
        residual_rms: fit.variance_factor?.sqrt(),
    })
}

fn residual_and_jacobian(p: &[f64; 3], x: &[f64]) -> (f64, [f64; 7]) {
    let (dx, dy) = (p[0] - x[0], p[1] - x[1]);
    let sig = x[6].exp();
    let (c1, s1) = (x[2].cos(), x[2].sin());
    let (c2, s2) = (x[3].cos(), x[3].sin());
    let z1 = (c1 * dx + s1 * dy) / sig;
    let z2 = (c2 * dx + s2 * dy) / sig;
    let ((a, pdf1), (b, pdf2)) = (normal_cdf_pdf(z1), normal_cdf_pdf(z2));
    let f = a + b - 2.0 * a * b;
    let r = x[4] + x[5] * f - p[2];
    let (g1, g2) = (
        x[5] * (1.0 - 2.0 * b) * pdf1 / sig,
        x[5] * (1.0 - 2.0 * a) * pdf2 / sig,
    );
    let j = [
        -g1 * c1 - g2 * c2,
        -g1 * s1 - g2 * s2,
        g1 * (-s1 * dx + c1 * dy),
        g2 * (-s2 * dx + c2 * dy),
        1.0,
        f,
        -(g1 * z1 + g2 * z2) * sig,
    ];
    (r, j)
}

/// The saddle model as a least-squares problem over x = (cx, cy, θ1, θ2, a, b, ln σ).
struct Saddle<'a> {
    samples: &'a [[f64; 3]],
}

impl Problem for Saddle<'_> {
    fn residual_count(&self) -> usize {
        self.samples.len()
    }
    fn parameter_count(&self) -> usize {
        7
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        for (ri, p) in r.iter_mut().zip(self.samples) {
            *ri = residual_and_jacobian(p, x).0;
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        for (i, p) in self.samples.iter().enumerate() {
            let (ri, row) = residual_and_jacobian(p, x);
            r[i] = ri;
            for (k, v) in row.iter().enumerate() {
                j[(i, k)] = *v;
            }
        }
        Ok(())
    }
}
