//! Online fit of the axis-scale expansion coefficient α from repeated measurements of reference
//! points on the axis.
//!
//! The catalog's `thermal_scale` term moves the tool along axis k by α·q_k·(T(q_k) − T_ref), T
//! interpolated between that axis's sensors. For a reference point j measured at time i, with
//! the lever x_i = q_k·(T(q_k) − T_ref) (m·K; the term's derivative with respect to α, see
//! [`crate::ThermalScaleCompensator::axis_lever`]) and y_i its error along the axis (measured −
//! nominal, less the drift of every other term), the model is
//!   y_i = c_j + α·x_i
//! with one static offset c_j per reference point (its geometric error: a pitch or backlash
//! error, a sensor's calibration offset times the lever, a squareness ...). α is therefore fixed
//! by how the error follows the temperature *changes*, not by the points' static errors. The
//! weighted least-squares solution is closed-form: per point the weighted means x̄_j, ȳ_j, then
//!   α = Σ w (x − x̄_j)(y − ȳ_j) / Σ w (x − x̄_j)²,   u²(α) = χ²/(n − 1 − m) / Σ w (x − x̄_j)²
//! (w = 1/variance of y; scaled by χ² per degree of freedom, as the growth fit is, so the
//! uncertainty is honest when the stated variances are not). The sums are kept per point
//! (about each point's first observation, for conditioning), so an observation costs O(1), a fit
//! O(points), and nothing grows with the length of a shift.
//!
//! Not modelled: the sensors' noise in x (errors in variables; α·q·σ_T, 0.01 µm at 1 m and
//! 0.02 K, far below a tracker's noise) and a drift of the points' static errors.

use crate::thermal_error::ThermalError;

/// A fit of α.
#[derive(Debug, Clone, PartialEq)]
pub struct ScaleFitResult {
    /// α, 1/K
    pub alpha: f64,
    /// u(α), 1/K (scaled by √(χ²/dof))
    pub alpha_uncertainty: f64,
    /// c_j of every reference point, m (NaN for a point without observations)
    pub offsets: Vec<f64>,
    /// χ² of the weighted residuals (with the stated variances)
    pub chi2: f64,
    pub observations: usize,
    /// n − 1 − (points with observations)
    pub degrees_of_freedom: usize,
}

impl ScaleFitResult {
    pub fn chi2_per_dof(&self) -> f64 {
        self.chi2 / self.degrees_of_freedom.max(1) as f64
    }
}

/// Weighted sums of one reference point's observations, about its first observation (x0, y0).
#[derive(Debug, Clone, Default)]
struct PointSums {
    n: usize,
    x0: f64,
    y0: f64,
    w: f64,
    wx: f64,
    wy: f64,
    wxx: f64,
    wxy: f64,
    wyy: f64,
}

impl PointSums {
    /// Centred sums (S_xx, S_xy, S_yy) and the weighted means (x̄, ȳ).
    fn centred(&self) -> (f64, f64, f64, f64, f64) {
        let (mx, my) = (self.wx / self.w, self.wy / self.w);
        (
            self.wxx - self.wx * mx,
            self.wxy - self.wx * my,
            self.wyy - self.wy * my,
            self.x0 + mx,
            self.y0 + my,
        )
    }
}

#[derive(Debug, Clone)]
pub struct ScaleFit {
    points: Vec<PointSums>,
}

impl ScaleFit {
    /// A fit over `points` reference points (indices 0..points).
    pub fn new(points: usize) -> Result<Self, ThermalError> {
        if points == 0 {
            return Err(ThermalError::BadParameter {
                name: "alpha fit".into(),
                reason: "needs at least one reference point".into(),
            });
        }
        Ok(Self {
            points: vec![PointSums::default(); points],
        })
    }

    pub fn points(&self) -> usize {
        self.points.len()
    }

    /// A measurement of reference point `point`: `lever` = q·(T(q) − T_ref) (m·K) at its time,
    /// `error` its error along the axis (m), `variance` that error's (m²).
    pub fn add_observation(
        &mut self,
        point: usize,
        lever: f64,
        error: f64,
        variance: f64,
    ) -> Result<(), ThermalError> {
        let count = self.points.len();
        let s = self
            .points
            .get_mut(point)
            .ok_or_else(|| ThermalError::BadParameter {
                name: "alpha fit".into(),
                reason: format!("reference point {point} of {count}"),
            })?;
        if !(lever.is_finite() && error.is_finite() && variance > 0.0 && variance.is_finite()) {
            return Err(ThermalError::NotFinite { what: format!("alpha-fit observation (lever {lever} m·K, error {error} m, variance {variance} m²; a zero variance cannot be weighted)") });
        }
        if s.n == 0 {
            (s.x0, s.y0) = (lever, error);
        }
        let (dx, dy, w) = (lever - s.x0, error - s.y0, 1.0 / variance);
        s.n += 1;
        s.w += w;
        s.wx += w * dx;
        s.wy += w * dy;
        s.wxx += w * dx * dx;
        s.wxy += w * dx * dy;
        s.wyy += w * dy * dy;
        Ok(())
    }

    pub fn observation_count(&self) -> usize {
        self.points.iter().map(|s| s.n).sum()
    }

    pub fn fit(&self) -> Result<ScaleFitResult, ThermalError> {
        let not_yet = |reason: String| ThermalError::BadParameter {
            name: "alpha fit".into(),
            reason,
        };
        let used: Vec<&PointSums> = self.points.iter().filter(|s| s.n > 0).collect();
        let n = self.observation_count();
        if n < used.len() + 2 {
            return Err(not_yet(format!(
                "needs at least {} measurements of {} reference points, has {n}",
                used.len() + 2,
                used.len()
            )));
        }
        let (mut sxx, mut sxy, mut syy, mut spread) = (0.0, 0.0, 0.0, 0.0);
        for s in &used {
            let (xx, xy, yy, _, _) = s.centred();
            sxx += xx.max(0.0);
            sxy += xy;
            syy += yy.max(0.0);
            spread += s.wxx;
        }
        // the levers at each point did not vary (beyond rounding): α is not separable from the offsets
        if !(sxx > 1e-12 * spread && sxx > 0.0) {
            return Err(not_yet("the temperatures at the reference points did not vary: alpha cannot be separated from the points' static errors".into()));
        }
        let alpha = sxy / sxx;
        let chi2 = (syy - alpha * sxy).max(0.0);
        let dof = n - 1 - used.len();
        let offsets = self
            .points
            .iter()
            .map(|s| {
                if s.n == 0 {
                    return f64::NAN;
                }
                let (_, _, _, mx, my) = s.centred();
                my - alpha * mx
            })
            .collect();
        Ok(ScaleFitResult {
            alpha,
            alpha_uncertainty: (chi2 / dof as f64 / sxx).sqrt(),
            offsets,
            chi2,
            observations: n,
            degrees_of_freedom: dof,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn gauss(rng: &mut ChaCha8Rng) -> f64 {
        let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Three reference points along X (0.2, 0.5, 0.8 m) with static errors of 5, −3 and 8 µm,
    /// measured every 10 min over 8 h while the scale warms from 19 to ~22 °C in work blocks,
    /// 2 µm noise per measurement. Truth α = 16e-6 1/K. Returns (fit, α_true).
    fn synthetic(seed: u64, noise: f64) -> (ScaleFit, f64) {
        let alpha = 16e-6;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut fit = ScaleFit::new(3).unwrap();
        let (q, c) = ([0.2, 0.5, 0.8], [5e-6, -3e-6, 8e-6]);
        for k in 0..48 {
            let t = k as f64 * 600.0;
            let temperature =
                19.0 + 0.35 * t / 3600.0 + if (t / 3600.0) % 2.5 < 1.5 { 0.6 } else { 0.0 };
            for j in 0..3 {
                let lever = q[j] * (temperature - 20.0);
                let y = c[j] + alpha * lever + noise * gauss(&mut rng);
                fit.add_observation(j, lever, y, noise * noise).unwrap();
            }
        }
        (fit, alpha)
    }

    #[test]
    fn recovers_alpha_within_its_uncertainty() {
        let (r, alpha) = {
            let (f, a) = synthetic(7, 2e-6);
            (f.fit().unwrap(), a)
        };
        eprintln!(
            "α = {:.3} ± {:.3} µm/(m·K) (truth {:.3}), χ²/dof {:.2}, offsets {:?} µm",
            r.alpha * 1e6,
            r.alpha_uncertainty * 1e6,
            alpha * 1e6,
            r.chi2_per_dof(),
            r.offsets.iter().map(|c| c * 1e6).collect::<Vec<_>>()
        );
        assert!(
            (r.alpha - alpha).abs() < 3.0 * r.alpha_uncertainty,
            "α {} ± {}",
            r.alpha,
            r.alpha_uncertainty
        );
        assert!(
            r.alpha_uncertainty < 0.05 * alpha,
            "informative: u(α) {}",
            r.alpha_uncertainty
        );
        assert_eq!((r.observations, r.degrees_of_freedom), (144, 140));
        for (c, want) in r.offsets.iter().zip([5e-6, -3e-6, 8e-6]) {
            assert!((c - want).abs() < 2e-6, "offset {c} vs {want}");
        }
    }

    #[test]
    fn the_stated_uncertainty_covers_the_truth_at_its_rate_over_seeds() {
        // 200 noise seeds: |α − α_true| < u(α) in ~68 % of them, < 2u in ~95 %
        let (mut within1, mut within2, n) = (0, 0, 200);
        for seed in 0..n {
            let (f, alpha) = synthetic(1000 + seed, 2e-6);
            let r = f.fit().unwrap();
            let z = (r.alpha - alpha).abs() / r.alpha_uncertainty;
            within1 += (z < 1.0) as u32;
            within2 += (z < 2.0) as u32;
        }
        let (c1, c2) = (within1 as f64 / n as f64, within2 as f64 / n as f64);
        eprintln!(
            "coverage: {:.1} % within 1σ, {:.1} % within 2σ",
            c1 * 100.0,
            c2 * 100.0
        );
        assert!((0.60..=0.76).contains(&c1), "1σ coverage {c1}");
        assert!((0.91..=0.99).contains(&c2), "2σ coverage {c2}");
    }

    #[test]
    fn exact_data_give_alpha_exactly() {
        let (f, alpha) = synthetic(1, 1e-15);
        let r = f.fit().unwrap();
        assert!(
            (r.alpha - alpha).abs() < 1e-12 * alpha.abs().max(1e-6) + 1e-15,
            "{}",
            r.alpha
        );
    }

    #[test]
    fn refuses_to_fit_too_early_or_without_temperature_change() {
        let mut f = ScaleFit::new(2).unwrap();
        f.add_observation(0, 0.4, 1e-6, 1e-12).unwrap();
        f.add_observation(1, 0.8, 2e-6, 1e-12).unwrap();
        f.add_observation(0, 0.4, 1.5e-6, 1e-12).unwrap();
        assert!(f.fit().unwrap_err().to_string().contains("at least 4"));
        f.add_observation(1, 0.8, 2.5e-6, 1e-12).unwrap();
        assert!(f.fit().unwrap_err().to_string().contains("did not vary"));
        assert!(
            f.add_observation(2, 0.8, 0.0, 1e-12).is_err(),
            "no such point"
        );
        assert!(f.add_observation(0, f64::NAN, 0.0, 1e-12).is_err());
        assert!(
            f.add_observation(0, 0.1, 0.0, 0.0).is_err(),
            "zero variance"
        );
        assert!(ScaleFit::new(0).is_err());
    }
}
