//! Sub-pixel step edges by fitting a blurred-step model to every pixel in a band around the
//! edge, and corners as intersections of two fitted edges (with covariance).
//!
//! Model for pixel centre p: I(p) = a + b·Φ(s(p)/σ) with the signed distance
//!   s(p) = n·p − d − κ·u²,  n = (cos θ, sin θ) towards the bright side,  u = t₀·(p − m₀),
//! where t₀, m₀ are the initial edge direction and midpoint (fixed). κ (1/px) lets the edge bend
//! into a parabola, which is what a straight printed edge becomes under lens distortion; without
//! it a line fit to a long distorted side misplaces the corners by a few hundredths of a pixel.
//! The model is symmetric about the edge, so a box-filtered (pixel-integrated) or Gaussian-
//! blurred edge is located without bias. Parameters by Levenberg–Marquardt (metrocell_solver); covariance
//! s²(JᵀJ)⁻¹ with s² the residual variance.

use image::GrayImage;
use metrocell_solver::{solve, NotEvaluable, Options, Problem};
use nalgebra::{DMatrix, Matrix2, Matrix3, Point2, Vector2};

/// Variance (px²) of the box a pixel integrates over: the smallest blur any sampled edge has.
const PIXEL_BOX_VARIANCE: f64 = 1.0 / 12.0;

/// A fitted edge: n·p − d − κ·(t₀·(p − m₀))² = 0, n = (cos θ, sin θ) towards the bright side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeLine {
    pub theta: f64,
    pub d: f64,
    /// Curvature coefficient κ (1/px) about `mid` along `tangent`; 0 for a straight edge.
    pub kappa: f64,
    pub tangent: Vector2<f64>,
    pub mid: Point2<f64>,
    /// Covariance of (θ, d, κ) in (rad, px, 1/px).
    pub cov: Matrix3<f64>,
    /// Dark level a and contrast b (grey levels), blur σ (px).
    pub dark: f64,
    pub contrast: f64,
    pub blur_sigma: f64,
    /// RMS of the model residuals (grey levels) and number of pixels used.
    pub residual_rms: f64,
    pub pixels: usize,
}

impl EdgeLine {
    pub fn normal(&self) -> Vector2<f64> {
        Vector2::new(self.theta.cos(), self.theta.sin())
    }

    /// Signed distance-like value s(p) (px); zero on the edge, positive on the bright side.
    pub fn signed(&self, p: &Point2<f64>) -> f64 {
        let u = self.tangent.dot(&(p - self.mid));
        self.normal().dot(&p.coords) - self.d - self.kappa * u * u
    }
}

/// Standard normal CDF via erfc (Numerical Recipes' Chebyshev fit, |rel. error| < 1.2e-7).
pub fn normal_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Φ(z) and φ(z) with one exponential (Abramowitz & Stegun 26.2.17, |error| < 7.5e-8).
#[inline]
pub fn normal_cdf_pdf(z: f64) -> (f64, f64) {
    let pdf = (-0.5 * z * z).exp() * 0.398_942_280_401_432_7;
    let t = 1.0 / (1.0 + 0.231_641_9 * z.abs());
    let poly = t
        * (0.319_381_530
            + t * (-0.356_563_782
                + t * (1.781_477_937 + t * (-1.821_255_978 + t * 1.330_274_429))));
    let upper = pdf * poly; // 1 − Φ(|z|)
    (if z >= 0.0 { 1.0 - upper } else { upper }, pdf)
}

#[cfg(test)]
fn normal_pdf(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Where to look for an edge: the segment p0→p1 (approximate), the unit normal towards the
/// bright side, the half-width of the pixel band, and the fraction trimmed at each end.
#[derive(Debug, Clone, Copy)]
pub struct EdgeWindow {
    pub p0: [f64; 2],
    pub p1: [f64; 2],
    pub bright_normal: [f64; 2],
    pub band: f64,
    pub trim: f64,
}

/// Fit a step edge inside `win`. Two passes: the pixel band is re-centred on the first fit.
/// None when there are too few pixels, no contrast, or the fit does not converge.
pub fn fit_step_edge(img: &GrayImage, win: &EdgeWindow) -> Option<EdgeLine> {
    let n0 = Vector2::new(win.bright_normal[0], win.bright_normal[1]).try_normalize(1e-12)?;
    let (p0, p1) = (
        Vector2::new(win.p0[0], win.p0[1]),
        Vector2::new(win.p1[0], win.p1[1]),
    );
    let tangent = (p1 - p0).try_normalize(1e-12)?;
    let mid = Point2::from((p0 + p1) / 2.0);
    let mut edge = EdgeLine {
        theta: n0.y.atan2(n0.x),
        d: n0.dot(&p0),
        kappa: 0.0,
        tangent,
        mid,
        cov: Matrix3::zeros(),
        dark: 0.0,
        contrast: 0.0,
        blur_sigma: 0.7,
        residual_rms: 0.0,
        pixels: 0,
    };
    for pass in 0..2 {
        // A sparse first pass to centre the band, then the full fit.
        let samples = collect_band(img, win, &edge, if pass == 0 { 300 } else { 700 })?;
        // Curvature only where it is observable: lens-distortion sag grows with the square of
        // the side length and is negligible below ~60 px, where κ would only add variance.
        let fit_kappa = pass == 1 && (p1 - p0).norm() >= 60.0;
        edge = levenberg_marquardt(&samples, &edge, win.band, fit_kappa)?;
    }
    Some(edge)
}

/// Pixels (x, y, value) within ±band of the current edge and inside the trimmed segment.
fn collect_band(
    img: &GrayImage,
    win: &EdgeWindow,
    edge: &EdgeLine,
    max_samples: usize,
) -> Option<Vec<[f64; 3]>> {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let p0 = Vector2::new(win.p0[0], win.p0[1]);
    let p1 = Vector2::new(win.p1[0], win.p1[1]);
    let len = (p1 - p0).norm();
    if len < 3.0 {
        return None;
    }
    let t = (p1 - p0) / len;
    let pad = win.band + 2.0;
    let xmin = (p0.x.min(p1.x) - pad).floor().max(0.0) as i64;
    let xmax = (p0.x.max(p1.x) + pad).ceil().min((w - 1) as f64) as i64;
    let ymin = (p0.y.min(p1.y) - pad).floor().max(0.0) as i64;
    let ymax = (p0.y.max(p1.y) + pad).ceil().min((h - 1) as f64) as i64;
    // Per row, only the columns near the edge can pass the band test (a diagonal side's
    // bounding box is mostly far from it): |n·p − d| ≤ band + |κ|·u² with |u| ≤ reach, plus a
    // pixel of margin so that the exact test below decides.
    let n = edge.normal();
    let reach = 0.5 * len + 2.0 * pad;
    let slack = win.band + edge.kappa.abs() * reach * reach + 1.0;
    let mut out = Vec::new();
    for y in ymin..=ymax {
        let (mut xa, mut xb) = (xmin, xmax);
        if n.x.abs() > 0.2 {
            let c = edge.d - n.y * y as f64;
            let (u0, u1) = ((c - slack) / n.x, (c + slack) / n.x);
            xa = xa.max(u0.min(u1).floor() as i64);
            xb = xb.min(u0.max(u1).ceil() as i64);
        }
        for x in xa..=xb {
            let p = Point2::new(x as f64, y as f64);
            let u = t.dot(&(p.coords - p0)) / len;
            if u < win.trim || u > 1.0 - win.trim {
                continue;
            }
            if edge.signed(&p).abs() > win.band {
                continue;
            }
            out.push([p.x, p.y, img.get_pixel(x as u32, y as u32)[0] as f64]);
        }
    }
    // Long sides carry far more pixels than the fit needs: keep whole cross-sections at evenly
    // spaced stations along the edge. (Taking every k-th pixel in scan order aliases with the
    // band's width and can drop the two pixel columns next to a vertical edge altogether.)
    if out.len() > max_samples {
        let keep_every = out.len().div_ceil(max_samples) as i64;
        out.retain(|s| {
            let station = t.dot(&(Vector2::new(s[0], s[1]) - p0)).floor() as i64;
            station.rem_euclid(keep_every) == 0
        });
    }
    (out.len() >= 12).then_some(out)
}

/// The blurred-step model over x = (θ, d, κ, a, b, ln σ, a₁, b₁) with dark level a + a₁·v and
/// contrast b + b₁·v, v = u / half-length (illumination changing along the edge).
struct StepEdge<'a> {
    samples: &'a [[f64; 3]],
    /// Per sample (u, v): position along the start edge and its share of the half-length.
    along: Vec<(f64, f64)>,
}

impl StepEdge<'_> {
    /// Residual (model − pixel) of sample i and, if asked, its Jacobian row.
    fn row(&self, x: &[f64], i: usize, jac: Option<&mut [f64; 8]>) -> f64 {
        // Pixels integrate the image over their area, a box of variance 1/12 px², on top of the
        // optical blur exp(x5): without that floor a perfectly sharp step (synthetic or printed
        // markers) leaves the edge position undetermined within a pixel and the fit fails.
        let optical2 = (2.0 * x[5]).exp();
        let (c, s, sig) = (
            x[0].cos(),
            x[0].sin(),
            (optical2 + PIXEL_BOX_VARIANCE).sqrt(),
        );
        let p = &self.samples[i];
        let (u, v) = self.along[i];
        let z = (c * p[0] + s * p[1] - x[1] - x[2] * u * u) / sig;
        let (cdf, pdf) = normal_cdf_pdf(z);
        let contrast = x[4] + x[7] * v;
        if let Some(j) = jac {
            let g = contrast * pdf / sig;
            *j = [
                g * (-s * p[0] + c * p[1]),
                -g,
                -g * u * u,
                1.0,
                cdf,
                -contrast * pdf * z * optical2 / (sig * sig),
                v,
                cdf * v,
            ];
        }
        x[3] + x[6] * v + contrast * cdf - p[2]
    }
}

impl Problem for StepEdge<'_> {
    fn residual_count(&self) -> usize {
        self.samples.len()
    }
    fn parameter_count(&self) -> usize {
        8
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        for (i, ri) in r.iter_mut().enumerate() {
            *ri = self.row(x, i, None);
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        let mut row = [0.0; 8];
        for (i, ri) in r.iter_mut().enumerate() {
            *ri = self.row(x, i, Some(&mut row));
            for (k, v) in row.iter().enumerate() {
                j[(i, k)] = *v;
            }
        }
        Ok(())
    }
}

/// Fits the step-edge model to `samples` from `start` (metrocell_solver's Levenberg–Marquardt).
/// κ is held at its start value unless `fit_kappa`.
fn levenberg_marquardt(
    samples: &[[f64; 3]],
    start: &EdgeLine,
    band: f64,
    fit_kappa: bool,
) -> Option<EdgeLine> {
    let (tg, mid) = (start.tangent, start.mid);
    // Initial levels from the two sides of the start edge.
    let (mut lo, mut nlo, mut hi, mut nhi) = (0.0, 0, 0.0, 0);
    for s in samples {
        let dist = start.signed(&Point2::new(s[0], s[1]));
        if dist < -0.5 * band {
            lo += s[2];
            nlo += 1;
        } else if dist > 0.5 * band {
            hi += s[2];
            nhi += 1;
        }
    }
    if nlo == 0 || nhi == 0 {
        return None;
    }
    let (a0, b0) = (lo / nlo as f64, hi / nhi as f64 - lo / nlo as f64);
    if b0 <= 0.0 {
        return None;
    }
    let u: Vec<f64> = samples
        .iter()
        .map(|p| tg.x * (p[0] - mid.x) + tg.y * (p[1] - mid.y))
        .collect();
    let half = u.iter().fold(1.0, |a: f64, v| a.max(v.abs()));
    let problem = StepEdge {
        samples,
        along: u.iter().map(|&u| (u, u / half)).collect(),
    };
    let x0 = [
        start.theta,
        start.d,
        start.kappa,
        a0,
        b0,
        start.blur_sigma.max(0.3).ln(),
        0.0,
        0.0,
    ];
    // Optical blur between 0.05 and 20 px (ln σ in [−3, 3]); below 0.05 px the pixel box
    // dominates and the blur stops being observable (its column of JᵀJ would vanish).
    let (inf, ninf) = (f64::INFINITY, f64::NEG_INFINITY);
    let options = Options {
        bounds: Some((
            vec![ninf, ninf, ninf, ninf, ninf, -3.0, ninf, ninf],
            vec![inf, inf, inf, inf, inf, 3.0, inf, inf],
        )),
        fixed: vec![false, false, !fit_kappa, false, false, false, false, false],
        max_iterations: 30,
        // Converged when a step changes the cost by < 1e-9 of itself: parameters then move by
        // well under 1 % of their standard uncertainty.
        ftol: 1e-9,
        xtol: 1e-8,
        gtol: 1e-10,
        ..Options::default()
    };
    let fit = solve(&problem, &x0, &options).ok()?;
    let x = &fit.x;
    if x[4] - x[7].abs() <= 0.0 || !x.iter().all(|v| v.is_finite()) {
        return None;
    }
    let cov = fit.covariance()?;
    Some(EdgeLine {
        theta: x[0],
        d: x[1],
        kappa: x[2],
        tangent: tg,
        mid,
        cov: cov.fixed_view::<3, 3>(0, 0).into_owned(),
        dark: x[3],
        contrast: x[4],
        blur_sigma: ((2.0 * x[5]).exp() + PIXEL_BOX_VARIANCE).sqrt(),
        residual_rms: fit.variance_factor?.sqrt(),
        pixels: samples.len(),
    })
}

/// Intersection of two edges (Newton from the straight-line intersection) and its 2×2
/// covariance by first-order propagation of the edges' independent (θ, d, κ) covariances.
/// None for (near-)parallel edges or when Newton does not converge.
pub fn intersect(l1: &EdgeLine, l2: &EdgeLine) -> Option<(Point2<f64>, Matrix2<f64>)> {
    let (n1, n2) = (l1.normal(), l2.normal());
    let m = Matrix2::new(n1.x, n1.y, n2.x, n2.y);
    if m.determinant().abs() < 1e-6 {
        return None;
    }
    let mut p = Point2::from(m.try_inverse()? * Vector2::new(l1.d, l2.d));
    // Gradient of s(p) for one edge.
    let grad = |l: &EdgeLine, p: &Point2<f64>| {
        l.normal() - 2.0 * l.kappa * l.tangent.dot(&(p - l.mid)) * l.tangent
    };
    let mut converged = false;
    for _ in 0..20 {
        let f = Vector2::new(l1.signed(&p), l2.signed(&p));
        let (g1, g2) = (grad(l1, &p), grad(l2, &p));
        let jp = Matrix2::new(g1.x, g1.y, g2.x, g2.y);
        let step = jp.try_inverse()? * f;
        p -= step;
        if step.norm() < 1e-10 {
            converged = true;
            break;
        }
    }
    if !converged {
        return None;
    }
    let (g1, g2) = (grad(l1, &p), grad(l2, &p));
    let jp_inv = Matrix2::new(g1.x, g1.y, g2.x, g2.y).try_inverse()?;
    // ∂s/∂(θ, d, κ) for one edge at p.
    let dparams = |l: &EdgeLine| {
        let u = l.tangent.dot(&(p - l.mid));
        nalgebra::RowVector3::new(-l.theta.sin() * p.x + l.theta.cos() * p.y, -1.0, -u * u)
    };
    let (r1, r2) = (dparams(l1), dparams(l2));
    // dp = −Jp⁻¹ · blockdiag(r1, r2) · dparams
    let var1 = (r1 * l1.cov * r1.transpose())[(0, 0)];
    let var2 = (r2 * l2.cov * r2.transpose())[(0, 0)];
    let cov = jp_inv * Matrix2::new(var1, 0.0, 0.0, var2) * jp_inv.transpose();
    Some((p, cov))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_values() {
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-7);
        assert!((normal_cdf(1.0) - 0.841344746).abs() < 2e-7);
        assert!((normal_cdf(-2.0) - 0.022750132).abs() < 2e-7);
        for z in [-3.0, -1.0, -0.2, 0.0, 0.7, 2.5] {
            let (c, p) = normal_cdf_pdf(z);
            assert!((c - normal_cdf(z)).abs() < 3e-7, "Φ({z})");
            assert!((p - normal_pdf(z)).abs() < 1e-15);
        }
    }

    /// A box-filtered oblique step rendered analytically by supersampling is located < 0.01 px.
    #[test]
    fn oblique_edge_located_to_hundredths() {
        let (theta, d) = (0.3f64, 20.4f64);
        let (c, s) = (theta.cos(), theta.sin());
        let img = GrayImage::from_fn(40, 40, |x, y| {
            let mut acc = 0.0f64;
            for j in 0..16 {
                for i in 0..16 {
                    let px = x as f64 - 0.5 + (i as f64 + 0.5) / 16.0;
                    let py = y as f64 - 0.5 + (j as f64 + 0.5) / 16.0;
                    acc += if c * px + s * py > d { 220.0 } else { 30.0 };
                }
            }
            image::Luma([(acc / 256.0).round() as u8])
        });
        // Approximate segment along the line, a bit off.
        let p_on = |u: f64| [c * (d + 0.6) - s * u, s * (d + 0.6) + c * u];
        let win = EdgeWindow {
            p0: p_on(-5.0),
            p1: p_on(25.0),
            bright_normal: [c, s],
            band: 3.0,
            trim: 0.05,
        };
        let e = fit_step_edge(&img, &win).unwrap();
        assert!((e.theta - theta).abs() < 1e-3, "theta {}", e.theta);
        assert!((e.d - d).abs() < 0.01, "d {}", e.d);
    }
}
