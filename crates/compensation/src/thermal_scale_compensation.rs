//! Removing the thermal growth of the axis scales from measured points, online.
//!
//! The `thermal_scale` term (metrocell-physics) says the tool overshoots the commanded axis
//! coordinate q_k by α·q_k·(T(q_k) − T_ref) along axis k, T(q) interpolated between the sensors
//! on that axis. A point measured while the machine is warm is therefore corrected by
//! subtracting that displacement, evaluated at the point's nominal coordinates (the commanded
//! axis positions). Its covariance grows by the uncertainty of α and of the temperatures.

use metrocell_physics::thermal::thermal_scale::interpolate_temperature;
use nalgebra::{Matrix3, Vector3};

/// Where a temperature sensor sits: on which axis (0 = x, 1 = y, 2 = z) and at which axis
/// coordinate (m).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSensorPlacement {
    pub name: String,
    pub axis: usize,
    pub position: f64,
}

/// A temperature reading: value (°C) and variance (K²), as sensor_msgs/Temperature carries.
pub type Reading = (f64, f64);

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ThermalError {
    #[error("sensor '{sensor}': axis index {axis} is not 0 (x), 1 (y) or 2 (z)")]
    BadAxis { sensor: String, axis: usize },
    #[error("sensor '{0}' is listed twice")]
    DuplicateSensor(String),
    #[error("no reading yet from sensor '{0}' (axis {1}); compensation on that axis waits for it")]
    NoReading(String, &'static str),
    #[error("alpha {0} 1/K is not a plausible expansion coefficient (expected 0..5e-5 1/K)")]
    BadAlpha(f64),
}

/// Thermal-scale compensation of the three axes with one expansion coefficient.
#[derive(Debug, Clone)]
pub struct ThermalScaleCompensator {
    /// 1/K
    pub alpha: f64,
    /// standard uncertainty of alpha, 1/K
    pub alpha_uncertainty: f64,
    /// °C
    pub reference_temperature: f64,
    sensors: Vec<AxisSensorPlacement>,
}

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

impl ThermalScaleCompensator {
    pub fn new(
        alpha: f64,
        alpha_uncertainty: f64,
        reference_temperature: f64,
        sensors: Vec<AxisSensorPlacement>,
    ) -> Result<Self, ThermalError> {
        if !(alpha.is_finite() && (0.0..=5e-5).contains(&alpha)) {
            return Err(ThermalError::BadAlpha(alpha));
        }
        for (i, s) in sensors.iter().enumerate() {
            if s.axis > 2 {
                return Err(ThermalError::BadAxis { sensor: s.name.clone(), axis: s.axis });
            }
            if sensors[..i].iter().any(|o| o.name == s.name) {
                return Err(ThermalError::DuplicateSensor(s.name.clone()));
            }
        }
        Ok(Self { alpha, alpha_uncertainty, reference_temperature, sensors })
    }

    pub fn sensors(&self) -> &[AxisSensorPlacement] {
        &self.sensors
    }

    /// Whether axis `k` has any sensor (an axis without one is left uncorrected).
    pub fn covers(&self, k: usize) -> bool {
        self.sensors.iter().any(|s| s.axis == k)
    }

    /// Temperature (°C) and its variance at coordinate q of axis k, interpolated between that
    /// axis's sensors. `reading(name)` gives a sensor's latest reading.
    fn temperature_at(&self, k: usize, q: f64, reading: &dyn Fn(&str) -> Option<Reading>) -> Result<Reading, ThermalError> {
        let mut pts: Vec<(f64, Reading)> = Vec::new();
        for s in self.sensors.iter().filter(|s| s.axis == k) {
            let r = reading(&s.name).ok_or_else(|| ThermalError::NoReading(s.name.clone(), AXIS_NAMES[k]))?;
            pts.push((s.position, r));
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let t = interpolate_temperature(&pts.iter().map(|(p, r)| (*p, r.0)).collect::<Vec<_>>(), q);
        // The interpolation weights are at most 1 and sum to 1; the larger neighbour variance is
        // a safe (slightly pessimistic) bound for the interpolated one.
        let var = pts.iter().map(|(_, r)| r.1).fold(0.0, f64::max);
        Ok((t, var))
    }

    /// Mean scale strain of axis k (m/m) over its sensors and its variance: what a supervisor
    /// reads as "X is currently +23 µm/m long".
    pub fn axis_strain(&self, k: usize, reading: &dyn Fn(&str) -> Option<Reading>) -> Result<(f64, f64), ThermalError> {
        let on_axis: Vec<&AxisSensorPlacement> = self.sensors.iter().filter(|s| s.axis == k).collect();
        let mut sum = 0.0;
        let mut var_sum = 0.0;
        for s in &on_axis {
            let r = reading(&s.name).ok_or_else(|| ThermalError::NoReading(s.name.clone(), AXIS_NAMES[k]))?;
            sum += r.0;
            var_sum += r.1;
        }
        let n = on_axis.len().max(1) as f64;
        let dt = sum / n - self.reference_temperature;
        let var_t = var_sum / (n * n);
        let strain = self.alpha * dt;
        let var = self.alpha * self.alpha * var_t + dt * dt * self.alpha_uncertainty * self.alpha_uncertainty;
        Ok((strain, var))
    }

    /// The compensated point and covariance for a point measured at `nominal` (the commanded
    /// axis coordinates, m) with `measured` and covariance `cov` (m²).
    pub fn compensate(
        &self,
        nominal: &Vector3<f64>,
        measured: &Vector3<f64>,
        cov: &Matrix3<f64>,
        reading: &dyn Fn(&str) -> Option<Reading>,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ThermalError> {
        let mut out = *measured;
        let mut out_cov = *cov;
        for k in 0..3 {
            if !self.covers(k) {
                continue;
            }
            let q = nominal[k];
            let (t, var_t) = self.temperature_at(k, q, reading)?;
            let dt = t - self.reference_temperature;
            out[k] -= self.alpha * q * dt;
            out_cov[(k, k)] += (self.alpha * q).powi(2) * var_t + (q * dt * self.alpha_uncertainty).powi(2);
        }
        Ok((out, out_cov))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_physics::{configure, Signals, TermConfig};

    fn two_sensor_x() -> ThermalScaleCompensator {
        ThermalScaleCompensator::new(
            11.5e-6,
            0.5e-6,
            20.0,
            vec![
                AxisSensorPlacement { name: "x_left".into(), axis: 0, position: 0.0 },
                AxisSensorPlacement { name: "x_right".into(), axis: 0, position: 1.0 },
            ],
        )
        .unwrap()
    }

    fn readings(name: &str) -> Option<Reading> {
        match name {
            "x_left" => Some((22.0, 0.01)),
            "x_right" => Some((24.0, 0.01)),
            _ => None,
        }
    }

    #[test]
    fn removes_exactly_what_the_physics_term_predicts() {
        // The same displacement from the catalog's thermal_scale term, configured like the
        // compensator, must be removed to the last bit.
        let cfg: TermConfig = serde_yaml_from(
            "id: thermal_scale\noptions: {axis: x, sensors: [{name: x_left, position: 0.0}, {name: x_right, position: 1.0}]}\nparams: {alpha: 1.15e-5}\n",
        );
        let term = configure(&cfg).unwrap();
        let q = 0.75;
        let mut s = Signals::default().with_positions(Vector3::new(q, 0.2, 0.1));
        s.temperatures.insert("x_left".into(), 22.0);
        s.temperatures.insert("x_right".into(), 24.0);
        let d = term.term.predict(&term.params, &s).unwrap().value;
        let true_point = Vector3::new(q, 0.2, 0.1);
        let measured = true_point + Vector3::new(d[0], d[1], d[2]);
        let (c, _) = two_sensor_x().compensate(&true_point, &measured, &Matrix3::zeros(), &readings).unwrap();
        assert!((c - true_point).norm() < 1e-15, "left {:e} m", (c - true_point).norm());
        // 11.5e-6 · 0.75 m · 3.5 K = 30.19 µm removed along x.
        assert!(((measured - c)[0] - 30.1875e-6).abs() < 1e-12);
    }

    #[test]
    fn covariance_grows_by_alpha_and_temperature_uncertainty() {
        let (_, cov) = two_sensor_x()
            .compensate(&Vector3::new(1.0, 0.0, 0.0), &Vector3::zeros(), &(Matrix3::identity() * 1e-12), &readings)
            .unwrap();
        let expect = 1e-12 + (11.5e-6f64).powi(2) * 0.01 + (4.0 * 0.5e-6f64).powi(2);
        assert!((cov[(0, 0)] - expect).abs() < 1e-24);
        assert_eq!(cov[(1, 1)], 1e-12, "y has no sensor and is untouched");
    }

    #[test]
    fn strain_of_a_warm_axis() {
        let (e, var) = two_sensor_x().axis_strain(0, &readings).unwrap();
        assert!((e - 11.5e-6 * 3.0).abs() < 1e-18);
        assert!(var > 0.0);
    }

    #[test]
    fn missing_sensor_is_named() {
        let err = two_sensor_x().compensate(&Vector3::new(0.5, 0.0, 0.0), &Vector3::zeros(), &Matrix3::zeros(), &|n| {
            (n == "x_left").then_some((21.0, 0.0))
        });
        assert_eq!(err.unwrap_err(), ThermalError::NoReading("x_right".into(), "x"));
    }

    #[test]
    fn rejects_bad_configuration() {
        assert!(matches!(ThermalScaleCompensator::new(1.0, 0.0, 20.0, vec![]), Err(ThermalError::BadAlpha(_))));
        let dup = vec![
            AxisSensorPlacement { name: "a".into(), axis: 0, position: 0.0 },
            AxisSensorPlacement { name: "a".into(), axis: 1, position: 0.0 },
        ];
        assert_eq!(ThermalScaleCompensator::new(1e-5, 0.0, 20.0, dup).unwrap_err(), ThermalError::DuplicateSensor("a".into()));
    }

    fn serde_yaml_from(text: &str) -> TermConfig {
        serde_yaml::from_str(text).unwrap()
    }
}
