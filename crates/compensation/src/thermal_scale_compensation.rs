//! Removing the thermal growth of the axis scales from measured points, online.
//!
//! The catalog's `thermal_scale` term (metrocell-physics) says the tool overshoots the commanded
//! axis coordinate q_k by α·q_k·(T(q_k) − T_ref) along axis k, T(q) interpolated between the
//! sensors on that axis. A point measured while the machine is warm is therefore corrected by
//! subtracting that displacement, evaluated by the catalog term itself at the point's nominal
//! coordinates (the commanded axis positions). α is validated against the catalog's range for
//! `thermal_scale.alpha`. The covariance grows by u(α) and by each sensor's variance through its
//! interpolation weight.

use metrocell_physics::{configure, ConfigValue, ConfiguredTerm, PhysicsError, TermConfig};
use nalgebra::{Matrix3, Vector3};

use crate::thermal_drift::{total_drift, TemperatureSensitivity, TermDrift};
pub use crate::thermal_error::{Reading, ThermalError};
use crate::thermal_signals::thermal_signals;

/// Where a temperature sensor sits: on which axis (0 = x, 1 = y, 2 = z) and at which axis
/// coordinate (m).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSensorPlacement {
    pub name: String,
    pub axis: usize,
    pub position: f64,
}

/// Thermal-scale compensation of the three axes with one expansion coefficient.
#[derive(Debug)]
pub struct ThermalScaleCompensator {
    /// 1/K
    pub alpha: f64,
    /// standard uncertainty of alpha, 1/K
    pub alpha_uncertainty: f64,
    /// °C
    pub reference_temperature: f64,
    sensors: Vec<AxisSensorPlacement>,
    /// The catalog term of each covered axis.
    terms: Vec<(usize, ConfiguredTerm)>,
}

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// The catalog's `thermal_scale` term for one axis, configured like the compensator.
fn catalog_term(
    axis: usize,
    sensors: &[&AxisSensorPlacement],
    alpha: f64,
    reference_temperature: f64,
) -> Result<ConfiguredTerm, PhysicsError> {
    let sensor = |s: &AxisSensorPlacement| {
        ConfigValue::Map(
            [
                ("name".to_string(), ConfigValue::Text(s.name.clone())),
                ("position".to_string(), ConfigValue::Number(s.position)),
            ]
            .into_iter()
            .collect(),
        )
    };
    configure(&TermConfig {
        id: "thermal_scale".into(),
        options: [
            (
                "axis".to_string(),
                ConfigValue::Text(AXIS_NAMES[axis].into()),
            ),
            (
                "sensors".to_string(),
                ConfigValue::List(sensors.iter().map(|s| sensor(s)).collect()),
            ),
            (
                "reference_temperature".to_string(),
                ConfigValue::Number(reference_temperature),
            ),
        ]
        .into_iter()
        .collect(),
        params: [("alpha".to_string(), ConfigValue::Number(alpha))]
            .into_iter()
            .collect(),
        use_defaults: false,
    })
}

impl ThermalScaleCompensator {
    pub fn new(
        alpha: f64,
        alpha_uncertainty: f64,
        reference_temperature: f64,
        sensors: Vec<AxisSensorPlacement>,
    ) -> Result<Self, ThermalError> {
        if !alpha.is_finite() {
            return Err(ThermalError::BadAlpha(alpha));
        }
        if !(alpha_uncertainty >= 0.0 && alpha_uncertainty.is_finite()) {
            return Err(ThermalError::BadParameter {
                name: "alpha_uncertainty".into(),
                reason: format!("must be ≥ 0 and finite, got {alpha_uncertainty}"),
            });
        }
        if !reference_temperature.is_finite() {
            return Err(ThermalError::NotFinite {
                what: "reference_temperature".into(),
            });
        }
        for (i, s) in sensors.iter().enumerate() {
            if s.axis > 2 {
                return Err(ThermalError::BadAxis {
                    sensor: s.name.clone(),
                    axis: s.axis,
                });
            }
            if sensors[..i].iter().any(|o| o.name == s.name) {
                return Err(ThermalError::DuplicateSensor(s.name.clone()));
            }
            if !s.position.is_finite() {
                return Err(ThermalError::NotFinite {
                    what: format!("position of sensor '{}'", s.name),
                });
            }
        }
        let mut terms = Vec::new();
        for k in 0..3 {
            let on_axis: Vec<&AxisSensorPlacement> =
                sensors.iter().filter(|s| s.axis == k).collect();
            if on_axis.is_empty() {
                continue;
            }
            let term =
                catalog_term(k, &on_axis, alpha, reference_temperature).map_err(|e| match e {
                    PhysicsError::OutOfRange { .. } => ThermalError::BadAlpha(alpha),
                    other => ThermalError::Physics(other),
                })?;
            terms.push((k, term));
        }
        if terms.is_empty() {
            // no sensor: still validate α against the catalog range
            catalog_term(
                0,
                &[&AxisSensorPlacement {
                    name: "-".into(),
                    axis: 0,
                    position: 0.0,
                }],
                alpha,
                reference_temperature,
            )
            .map_err(|_| ThermalError::BadAlpha(alpha))?;
        }
        Ok(Self {
            alpha,
            alpha_uncertainty,
            reference_temperature,
            sensors,
            terms,
        })
    }

    pub fn sensors(&self) -> &[AxisSensorPlacement] {
        &self.sensors
    }

    /// Whether axis `k` has any sensor (an axis without one is left uncorrected).
    pub fn covers(&self, k: usize) -> bool {
        self.sensors.iter().any(|s| s.axis == k)
    }

    /// Catalog labels of the configured terms with their axis index, e.g. (0, `thermal_scale[x]`).
    /// The catalog term of axis k (0, 1, 2 = X, Y, Z), if the axis is covered.
    pub fn axis_term(&self, k: usize) -> Option<&ConfiguredTerm> {
        self.terms.iter().find(|(a, _)| *a == k).map(|(_, t)| t)
    }

    pub fn labels(&self) -> Vec<(usize, String)> {
        self.terms
            .iter()
            .map(|(k, t)| (*k, t.term.label()))
            .collect()
    }

    /// Mean scale strain of axis k (m/m) over its sensors and its variance: what a supervisor
    /// reads as "X is currently +23 µm/m long".
    pub fn axis_strain(
        &self,
        k: usize,
        reading: &dyn Fn(&str) -> Option<Reading>,
    ) -> Result<(f64, f64), ThermalError> {
        let on_axis: Vec<&AxisSensorPlacement> =
            self.sensors.iter().filter(|s| s.axis == k).collect();
        let mut sum = 0.0;
        let mut var_sum = 0.0;
        for s in &on_axis {
            let r = reading(&s.name)
                .ok_or_else(|| ThermalError::NoReading(s.name.clone(), AXIS_NAMES[k]))?;
            sum += r.0;
            var_sum += r.1;
        }
        let n = on_axis.len().max(1) as f64;
        let dt = sum / n - self.reference_temperature;
        let var_t = var_sum / (n * n);
        let strain = self.alpha * dt;
        let var = self.alpha * self.alpha * var_t
            + dt * dt * self.alpha_uncertainty * self.alpha_uncertainty;
        Ok((strain, var))
    }

    /// The lever of α on axis k at `nominal`: ∂(displacement along the axis)/∂α =
    /// q_k·(T(q_k) − T_ref) in m·K, from the catalog term (what the online fit of α regresses
    /// the axis error on, [`crate::ScaleFit`]).
    pub fn axis_lever(
        &self,
        k: usize,
        nominal: &Vector3<f64>,
        reading: &dyn Fn(&str) -> Option<Reading>,
    ) -> Result<f64, ThermalError> {
        let (_, term) =
            self.terms
                .iter()
                .find(|(a, _)| *a == k)
                .ok_or_else(|| ThermalError::BadParameter {
                    name: "alpha fit".into(),
                    reason: format!(
                        "axis {} has no scale sensor",
                        AXIS_NAMES.get(k).copied().unwrap_or("?")
                    ),
                })?;
        let mut temps = Vec::new();
        for s in self.sensors.iter().filter(|s| s.axis == k) {
            let (t, _) = reading(&s.name)
                .ok_or_else(|| ThermalError::NoReading(s.name.clone(), AXIS_NAMES[k]))?;
            if !t.is_finite() {
                return Err(ThermalError::NotFinite {
                    what: format!("reading of sensor '{}'", s.name),
                });
            }
            temps.push((s.name.as_str(), t));
        }
        let j = term
            .term
            .jacobian(&term.params, &thermal_signals(nominal, &temps, &[]))?;
        Ok(j[(k, 0)])
    }

    /// Use `alpha` ± `alpha_uncertainty` from now on (an online fit), validated as at start-up.
    pub fn use_alpha(&mut self, alpha: f64, alpha_uncertainty: f64) -> Result<(), ThermalError> {
        *self = Self::new(
            alpha,
            alpha_uncertainty,
            self.reference_temperature,
            self.sensors.clone(),
        )?;
        Ok(())
    }

    /// The displacement the catalog terms predict at `nominal` (commanded axis coordinates, m),
    /// one [`TermDrift`] per covered axis.
    pub fn drift(
        &self,
        nominal: &Vector3<f64>,
        reading: &dyn Fn(&str) -> Option<Reading>,
    ) -> Result<Vec<TermDrift>, ThermalError> {
        let mut out = Vec::with_capacity(self.terms.len());
        for (k, term) in &self.terms {
            let on_axis: Vec<&AxisSensorPlacement> =
                self.sensors.iter().filter(|s| s.axis == *k).collect();
            let mut temps = Vec::with_capacity(on_axis.len());
            let mut variances = Vec::with_capacity(on_axis.len());
            for s in &on_axis {
                let (t, var) = reading(&s.name)
                    .ok_or_else(|| ThermalError::NoReading(s.name.clone(), AXIS_NAMES[*k]))?;
                if !(t.is_finite() && var.is_finite()) {
                    return Err(ThermalError::NotFinite {
                        what: format!("reading of sensor '{}'", s.name),
                    });
                }
                temps.push((s.name.as_str(), t));
                variances.push(var);
            }
            let p = &term.params;
            let s = thermal_signals(nominal, &temps, &[]);
            let d = term.term.predict(p, &s)?.value;
            let lever = term.term.jacobian(p, &s)?.column(0).into_owned();
            let lever = Vector3::new(lever[0], lever[1], lever[2]);
            // The term is linear in each temperature; with sensor i at T_ref + 1 K and the others
            // at T_ref it returns ∂d/∂T_i (α·q·w_i along the axis).
            let mut temperatures = Vec::with_capacity(on_axis.len());
            for (i, (name, _)) in temps.iter().enumerate() {
                let unit: Vec<(&str, f64)> = temps
                    .iter()
                    .enumerate()
                    .map(|(j, (n, _))| {
                        (
                            *n,
                            self.reference_temperature + if i == j { 1.0 } else { 0.0 },
                        )
                    })
                    .collect();
                let v = term
                    .term
                    .predict(p, &thermal_signals(nominal, &unit, &[]))?
                    .value;
                temperatures.push(TemperatureSensitivity {
                    input: name.to_string(),
                    d_drift_d_temperature: Vector3::new(v[0], v[1], v[2]),
                    variance: variances[i],
                });
            }
            out.push(TermDrift {
                displacement: Vector3::new(d[0], d[1], d[2]),
                temperatures,
                parameter_covariance: lever * lever.transpose() * self.alpha_uncertainty.powi(2),
            });
        }
        Ok(out)
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
        let (d, d_cov) = total_drift(&self.drift(nominal, reading)?);
        Ok((measured - d, cov + d_cov))
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
                AxisSensorPlacement {
                    name: "x_left".into(),
                    axis: 0,
                    position: 0.0,
                },
                AxisSensorPlacement {
                    name: "x_right".into(),
                    axis: 0,
                    position: 1.0,
                },
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
        let (c, _) = two_sensor_x()
            .compensate(&true_point, &measured, &Matrix3::zeros(), &readings)
            .unwrap();
        assert!(
            (c - true_point).norm() < 1e-15,
            "left {:e} m",
            (c - true_point).norm()
        );
        // 11.5e-6 · 0.75 m · 3.5 K = 30.19 µm removed along x.
        assert!(((measured - c)[0] - 30.1875e-6).abs() < 1e-12);
    }

    #[test]
    fn covariance_grows_by_alpha_and_temperature_uncertainty() {
        let (_, cov) = two_sensor_x()
            .compensate(
                &Vector3::new(1.0, 0.0, 0.0),
                &Vector3::zeros(),
                &(Matrix3::identity() * 1e-12),
                &readings,
            )
            .unwrap();
        let expect = 1e-12 + (11.5e-6f64).powi(2) * 0.01 + (4.0 * 0.5e-6f64).powi(2);
        assert!((cov[(0, 0)] - expect).abs() < 1e-24);
        assert_eq!(cov[(1, 1)], 1e-12, "y has no sensor and is untouched");
    }

    #[test]
    fn axis_lever_is_the_derivative_of_the_drift_in_alpha() {
        let mut c = two_sensor_x();
        let nominal = Vector3::new(0.75, 0.2, 0.1);
        // T(0.75) = 22 + 0.75·2 = 23.5 °C: lever 0.75 m · 3.5 K
        let lever = c.axis_lever(0, &nominal, &readings).unwrap();
        assert!((lever - 0.75 * 3.5).abs() < 1e-12, "{lever}");
        let (d, _) = total_drift(&c.drift(&nominal, &readings).unwrap());
        assert!((d.x - c.alpha * lever).abs() < 1e-18);
        assert!(c
            .axis_lever(1, &nominal, &readings)
            .unwrap_err()
            .to_string()
            .contains("axis y has no scale sensor"));
        c.use_alpha(16e-6, 0.2e-6).unwrap();
        let (d, cov) = total_drift(&c.drift(&nominal, &readings).unwrap());
        assert!((d.x - 16e-6 * lever).abs() < 1e-18, "the new alpha is used");
        assert!(
            cov[(0, 0)] >= (lever * 0.2e-6).powi(2) * (1.0 - 1e-12),
            "and its uncertainty"
        );
        assert!(matches!(
            c.use_alpha(1e-3, 0.0),
            Err(ThermalError::BadAlpha(_))
        ));
        assert_eq!(
            c.alpha, 16e-6,
            "a refused alpha leaves the compensator as it was"
        );
    }

    #[test]
    fn strain_of_a_warm_axis() {
        let (e, var) = two_sensor_x().axis_strain(0, &readings).unwrap();
        assert!((e - 11.5e-6 * 3.0).abs() < 1e-18);
        assert!(var > 0.0);
    }

    #[test]
    fn missing_sensor_is_named() {
        let err = two_sensor_x().compensate(
            &Vector3::new(0.5, 0.0, 0.0),
            &Vector3::zeros(),
            &Matrix3::zeros(),
            &|n| (n == "x_left").then_some((21.0, 0.0)),
        );
        assert_eq!(
            err.unwrap_err(),
            ThermalError::NoReading("x_right".into(), "x")
        );
    }

    #[test]
    fn rejects_bad_configuration() {
        assert!(matches!(
            ThermalScaleCompensator::new(1.0, 0.0, 20.0, vec![]),
            Err(ThermalError::BadAlpha(_))
        ));
        let dup = vec![
            AxisSensorPlacement {
                name: "a".into(),
                axis: 0,
                position: 0.0,
            },
            AxisSensorPlacement {
                name: "a".into(),
                axis: 1,
                position: 0.0,
            },
        ];
        assert_eq!(
            ThermalScaleCompensator::new(1e-5, 0.0, 20.0, dup).unwrap_err(),
            ThermalError::DuplicateSensor("a".into())
        );
    }

    fn serde_yaml_from(text: &str) -> TermConfig {
        serde_yaml::from_str(text).unwrap()
    }
}
