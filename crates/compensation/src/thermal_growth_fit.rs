//! Online fit of a lagged growth term from repeated measurements of a reference point.
//!
//! Model of the reference point's error along the growth direction n̂ (m):
//!   y(t) = c + g·(T_f(t; τ) − T_ref)
//! c the point's static error, g = L·α (m/K), T_f the sensor's first-order lag with time
//! constant τ evaluated at the measurement time from the readings up to it. y is linear in
//! (c, g) for a given τ: the fit is the workspace's separable time-constant fit
//! (`metrocell_solver::time_constant_fit`, 48 log-spaced scan points over the configured range),
//! x = T_f − T_ref. Its covariance of (c, g, τ) is scaled by the rule for relative variances,
//! χ²/(n − 3), up or down: the variance given for y is the measurement's alone, while y also
//! carries the temperature sensor's noise through the lag and the error of the other terms
//! subtracted from it, which nobody states; so the noise level is estimated from the scatter.
//!
//! Readings and measurements are kept in a sliding window (`max_readings` readings; older ones
//! are dropped, and measurements older than the oldest reading no longer enter the fit); each
//! fit re-runs the lag over the window, so a fit costs O(readings × τ trials).

use metrocell_solver::{
    fit_time_constant, ChiSquareScaling, TimeConstantFitError, TimeConstantRow, TimeConstantSearch,
};
use nalgebra::{Matrix3, Vector3};

use crate::thermal_error::ThermalError;
use metrocell_physics::thermal::first_order_lag::FirstOrderLag;

/// A fit of (c, g, τ).
#[derive(Debug, Clone, PartialEq)]
pub struct GrowthFitResult {
    /// c, m
    pub offset: f64,
    /// g, m/K
    pub coefficient: f64,
    /// τ, s
    pub time_constant: f64,
    /// Covariance of (c, g, τ) in (m, m/K, s).
    pub covariance: Matrix3<f64>,
    /// Weighted-residual RMS in m (unweighted residuals' RMS).
    pub rms: f64,
    pub observations: usize,
    /// τ ended at an end of the search range: the data do not pin it down inside the range.
    pub at_bound: bool,
}

#[derive(Debug, Clone)]
pub struct GrowthFit {
    direction: Vector3<f64>,
    reference_temperature: f64,
    tau_range: (f64, f64),
    max_readings: usize,
    /// (t s, T °C, variance K²)
    readings: Vec<(f64, f64, f64)>,
    /// (t s, y m, variance m²)
    observations: Vec<(f64, f64, f64)>,
}

const SCAN_POINTS: usize = 48;

impl GrowthFit {
    pub fn new(
        direction: Vector3<f64>,
        reference_temperature: f64,
        tau_range: (f64, f64),
        max_readings: usize,
    ) -> Result<Self, ThermalError> {
        let n = direction.norm();
        if !(n > 0.0 && n.is_finite()) {
            return Err(ThermalError::BadParameter {
                name: "fit direction".into(),
                reason: format!("must be a non-zero finite vector, got {direction:?}"),
            });
        }
        if !(tau_range.0 > 0.0 && tau_range.1 > tau_range.0 && tau_range.1.is_finite()) {
            return Err(ThermalError::BadParameter {
                name: "fit_time_constant_range".into(),
                reason: format!(
                    "needs 0 < min < max, got [{}, {}] s",
                    tau_range.0, tau_range.1
                ),
            });
        }
        if max_readings < 2 {
            return Err(ThermalError::BadParameter {
                name: "fit_max_readings".into(),
                reason: format!("needs at least 2, got {max_readings}"),
            });
        }
        Ok(Self {
            direction: direction / n,
            reference_temperature,
            tau_range,
            max_readings,
            readings: Vec::new(),
            observations: Vec::new(),
        })
    }

    /// Add a sensor reading; one not later than the previous is ignored (false).
    pub fn add_reading(&mut self, time: f64, temperature: f64, variance: f64) -> bool {
        if self.readings.last().is_some_and(|r| time <= r.0)
            || !(temperature.is_finite() && variance.is_finite())
        {
            return false;
        }
        self.readings.push((time, temperature, variance));
        if self.readings.len() > self.max_readings {
            let drop = self.readings.len() - self.max_readings;
            self.readings.drain(..drop);
            let first = self.readings[0].0;
            self.observations.retain(|o| o.0 >= first);
        }
        true
    }

    /// Add a measurement of the reference point: `error` = measured − nominal (m) with its
    /// covariance (m²); its component along the growth direction enters the fit.
    pub fn add_observation(
        &mut self,
        time: f64,
        error: &Vector3<f64>,
        covariance: &Matrix3<f64>,
    ) -> Result<(), ThermalError> {
        if self.observations.last().is_some_and(|o| time < o.0) {
            return Err(ThermalError::BadParameter {
                name: "reference point".into(),
                reason: format!("measurement at {time} s is older than the previous one"),
            });
        }
        let y = self.direction.dot(error);
        let var = (self.direction.transpose() * covariance * self.direction)[0];
        if !(y.is_finite() && var > 0.0 && var.is_finite()) {
            return Err(ThermalError::NotFinite { what: format!("reference point measurement at {time} s (error {y} m, variance {var} m²; a zero variance cannot be weighted)") });
        }
        self.observations.push((time, y, var));
        Ok(())
    }

    pub fn observation_count(&self) -> usize {
        self.observations.len()
    }

    /// The lag over the window's readings with time constant τ (for the compensator to continue).
    pub fn lag(&self, tau: f64) -> FirstOrderLag {
        let mut lag = FirstOrderLag::new(tau);
        for (t, v, var) in &self.readings {
            lag.advance(*t, *v, *var);
        }
        lag
    }

    /// The rows of the separable fit at every measurement that has a reading before it:
    /// x = T_f − T_ref, ∂T_f/∂τ, y and its variance.
    fn design(&self, tau: f64) -> Vec<TimeConstantRow> {
        let mut lag = FirstOrderLag::new(tau);
        let mut out = Vec::with_capacity(self.observations.len());
        let mut r = 0;
        for &(t, y, variance) in &self.observations {
            while r < self.readings.len() && self.readings[r].0 <= t {
                let (tr, v, vv) = self.readings[r];
                lag.advance(tr, v, vv);
                r += 1;
            }
            if let Some((_, tf, dx_dtau, _)) = lag.output() {
                out.push(TimeConstantRow {
                    x: tf - self.reference_temperature,
                    dx_dtau,
                    y,
                    variance,
                });
            }
        }
        out
    }

    pub fn fit(&self) -> Result<GrowthFitResult, ThermalError> {
        let not_yet = |reason: String| ThermalError::BadParameter {
            name: "online fit".into(),
            reason,
        };
        let usable = self.design(self.tau_range.0).len();
        if usable < 4 {
            return Err(not_yet(format!(
                "needs at least 4 reference measurements after the first reading, has {usable}"
            )));
        }
        let search = TimeConstantSearch {
            range: self.tau_range,
            scan_points: SCAN_POINTS,
            scaling: ChiSquareScaling::RelativeVariances,
        };
        let fit = fit_time_constant(&|tau| self.design(tau), &search).map_err(|e| match e {
            TimeConstantFitError::TauUndetermined => not_yet(
                "τ cannot be determined (the lagged temperature does not depend on it)".into(),
            ),
            TimeConstantFitError::TooFewRows(n) => not_yet(format!(
                "needs at least 4 reference measurements after the first reading, has {n}"
            )),
            TimeConstantFitError::NoVariation | TimeConstantFitError::BadSearch => not_yet(
                "the temperatures did not vary: g cannot be separated from the offset".into(),
            ),
        })?;
        Ok(GrowthFitResult {
            offset: fit.offset,
            coefficient: fit.coefficient,
            time_constant: fit.tau,
            covariance: fit.covariance,
            rms: fit.rms,
            observations: fit.rows,
            at_bound: fit.at_bound,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn gauss(rng: &mut ChaCha8Rng) -> f64 {
        // Box–Muller
        let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// A column warming in work blocks, read every 10 s with 0.02 K noise; the reference point
    /// measured every 5 min with 1 µm noise along −z. Truth: c = 3 µm, g = 4 µm/K, τ = 20 min.
    fn synthetic(seed: u64) -> (GrowthFit, f64, f64) {
        let (g_true, tau_true, c_true) = (4e-6, 1200.0, 3e-6);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut fit =
            GrowthFit::new(Vector3::new(0.0, 0.0, -1.0), 20.0, (60.0, 1e5), 100_000).unwrap();
        let mut truth_lag = FirstOrderLag::new(tau_true);
        let mut column = 20.0;
        for k in 0..(8 * 360) {
            let t = k as f64 * 10.0;
            let heating = if (t / 3600.0) % 2.5 < 1.5 { 3.0 } else { 0.0 };
            column += (20.0 + heating - column) * (1.0 - (-10.0f64 / 3600.0).exp());
            truth_lag.advance(t, column, 0.0);
            fit.add_reading(t, column + 0.02 * gauss(&mut rng), 0.0004);
            if k % 30 == 29 {
                let (_, tf, _, _) = truth_lag.output().unwrap();
                let y = c_true + g_true * (tf - 20.0) + 1e-6 * gauss(&mut rng);
                fit.add_observation(
                    t,
                    &Vector3::new(0.0, 0.0, -y),
                    &(Matrix3::identity() * 1e-12),
                )
                .unwrap();
            }
        }
        (fit, g_true, tau_true)
    }

    #[test]
    fn recovers_coefficient_and_lag_within_their_uncertainty() {
        // "within" = within 3 standard uncertainties (k = 3), for each of three noise seeds
        for seed in [1, 2, 3] {
            let (fit, g_true, tau_true) = synthetic(seed);
            let r = fit.fit().unwrap();
            let (ug, utau) = (r.covariance[(1, 1)].sqrt(), r.covariance[(2, 2)].sqrt());
            eprintln!(
                "seed {seed}: g = {:.4} ± {:.4} µm/K, τ = {:.1} ± {:.1} s, rms {:.3} µm",
                r.coefficient * 1e6,
                ug * 1e6,
                r.time_constant,
                utau,
                r.rms * 1e6
            );
            assert!(
                (r.coefficient - g_true).abs() < 3.0 * ug,
                "g {} ± {ug}",
                r.coefficient
            );
            assert!(
                (r.time_constant - tau_true).abs() < 3.0 * utau,
                "τ {} ± {utau}",
                r.time_constant
            );
            // and the uncertainty is informative, not a wide net: g to better than 10 %, τ to 15 %
            assert!(
                ug < 0.1 * g_true && utau < 0.15 * tau_true,
                "u(g) {ug}, u(τ) {utau}"
            );
            assert!(!r.at_bound);
            assert!(
                (r.rms - 1e-6).abs() < 0.3e-6,
                "residual rms {} matches the 1 µm noise",
                r.rms
            );
        }
    }

    #[test]
    fn refuses_to_fit_too_early_or_without_temperature_change() {
        let mut fit = GrowthFit::new(Vector3::z(), 20.0, (60.0, 1e5), 1000).unwrap();
        for k in 0..100 {
            fit.add_reading(k as f64, 21.0, 0.0);
        }
        for k in 0..3 {
            fit.add_observation(10.0 * k as f64, &Vector3::zeros(), &Matrix3::identity())
                .unwrap();
        }
        assert!(fit.fit().unwrap_err().to_string().contains("at least 4"));
        fit.add_observation(40.0, &Vector3::zeros(), &Matrix3::identity())
            .unwrap();
        assert!(fit.fit().unwrap_err().to_string().contains("did not vary"));
        assert!(
            fit.add_observation(5.0, &Vector3::zeros(), &Matrix3::identity())
                .is_err(),
            "out of order"
        );
        assert!(fit
            .add_observation(
                50.0,
                &Vector3::new(f64::NAN, 0.0, 0.0),
                &Matrix3::identity()
            )
            .is_err());
        assert!(GrowthFit::new(Vector3::zeros(), 20.0, (60.0, 1e5), 10)
            .unwrap_err()
            .to_string()
            .contains("direction"));
        assert!(GrowthFit::new(Vector3::z(), 20.0, (600.0, 60.0), 10)
            .unwrap_err()
            .to_string()
            .contains("fit_time_constant_range"));
    }
}
