//! Removing the growth of a structural element (column, ram, head) from measured points: the
//! catalog's `thermal_growth` term, d = n̂·g·(T_f − T_ref), g = L·α (m/K), with T_f the
//! sensor's reading passed through a first-order lag of time constant τ (or the reading itself
//! when there is no lag).
//!
//! The lag is advanced here one reading at a time ([`FirstOrderLag`], the workspace's one lag
//! filter, crates/physics) and the catalog term is
//! evaluated on its output. Uncertainty: u(g) and u(τ) (through ∂T_f/∂τ), the filtered
//! reading variance, and the sensor's calibration uncertainty, which the lag does not average
//! down (a calibration error is the same in every reading).

use metrocell_physics::{configure, ConfigValue, ConfiguredTerm, PhysicsError, TermConfig};
use nalgebra::{Matrix2, Vector3};

use crate::thermal_drift::{TemperatureSensitivity, TermDrift};
use crate::thermal_error::ThermalError;
use crate::thermal_signals::thermal_signals;
use metrocell_physics::thermal::first_order_lag::FirstOrderLag;

/// One growth term as configured.
#[derive(Debug, Clone, PartialEq)]
pub struct GrowthSpec {
    pub sensor: String,
    /// Direction of the growth (normalised by the catalog term), machine frame.
    pub direction: Vector3<f64>,
    /// g, m/K
    pub coefficient: f64,
    /// u(g), m/K
    pub coefficient_uncertainty: f64,
    /// τ in s; `None` = no lag.
    pub time_constant: Option<f64>,
    /// u(τ), s
    pub time_constant_uncertainty: f64,
    /// °C
    pub reference_temperature: f64,
    /// Standard calibration uncertainty of the sensor, K.
    pub calibration_uncertainty: f64,
}

#[derive(Debug)]
pub struct GrowthCompensator {
    pub spec: GrowthSpec,
    term: ConfiguredTerm,
    /// Covariance of (g, τ) in use (τ row/column zero without lag).
    parameter_covariance: Matrix2<f64>,
    lag: FirstOrderLag,
    /// True while the parameters in use come from the online fit, not from the configuration.
    fitted: bool,
}

fn bad(name: &str, reason: String) -> ThermalError {
    ThermalError::BadParameter {
        name: name.into(),
        reason,
    }
}

fn catalog_term(
    spec: &GrowthSpec,
    coefficient: f64,
    time_constant: Option<f64>,
) -> Result<ConfiguredTerm, PhysicsError> {
    let d = spec.direction;
    let mut params = vec![("coefficient".to_string(), ConfigValue::Number(coefficient))];
    if let Some(tau) = time_constant {
        params.push(("time_constant".to_string(), ConfigValue::Number(tau)));
    }
    configure(&TermConfig {
        id: "thermal_growth".into(),
        options: [
            ("sensor".to_string(), ConfigValue::Text(spec.sensor.clone())),
            (
                "direction".to_string(),
                ConfigValue::List(vec![
                    ConfigValue::Number(d.x),
                    ConfigValue::Number(d.y),
                    ConfigValue::Number(d.z),
                ]),
            ),
            (
                "lag".to_string(),
                ConfigValue::Bool(time_constant.is_some()),
            ),
            (
                "reference_temperature".to_string(),
                ConfigValue::Number(spec.reference_temperature),
            ),
        ]
        .into_iter()
        .collect(),
        params: params.into_iter().collect(),
        use_defaults: false,
    })
}

impl GrowthCompensator {
    pub fn new(spec: GrowthSpec) -> Result<Self, ThermalError> {
        for (name, v) in [
            ("coefficient_uncertainty", spec.coefficient_uncertainty),
            ("time_constant_uncertainty", spec.time_constant_uncertainty),
            ("calibration_uncertainty", spec.calibration_uncertainty),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(bad(
                    &format!("{}: {name}", spec.sensor),
                    format!("must be ≥ 0 and finite, got {v}"),
                ));
            }
        }
        let term = catalog_term(&spec, spec.coefficient, spec.time_constant)?;
        let u_tau = if spec.time_constant.is_some() {
            spec.time_constant_uncertainty
        } else {
            0.0
        };
        let parameter_covariance = Matrix2::new(
            spec.coefficient_uncertainty.powi(2),
            0.0,
            0.0,
            u_tau * u_tau,
        );
        // Without lag the filter passes readings through (τ → 0 would divide by zero, so it is
        // simply not advanced past the latest reading: see `observe`).
        let lag = FirstOrderLag::new(spec.time_constant.unwrap_or(f64::MIN_POSITIVE));
        Ok(Self {
            spec,
            term,
            parameter_covariance,
            lag,
            fitted: false,
        })
    }

    /// Catalog label, e.g. `thermal_growth[column]`.
    pub fn label(&self) -> String {
        self.term.term.label()
    }

    /// The catalog term in use (options, current parameter values).
    pub fn catalog_term(&self) -> &ConfiguredTerm {
        &self.term
    }

    /// (name, unit, value) of the parameters in use, catalog order, and their covariance.
    pub fn parameters(&self) -> (Vec<(String, &'static str, f64)>, Matrix2<f64>) {
        let names = self
            .term
            .term
            .params()
            .into_iter()
            .zip(&self.term.params)
            .map(|(s, v)| (s.name, s.unit, *v))
            .collect();
        (names, self.parameter_covariance)
    }

    pub fn is_fitted(&self) -> bool {
        self.fitted
    }

    /// Feed a reading of this term's sensor at `time` (s). Returns false if it was older than the
    /// previous reading (ignored).
    pub fn observe(&mut self, time: f64, temperature: f64, variance: f64) -> bool {
        if self.spec.time_constant.is_none() {
            self.lag = FirstOrderLag::new(f64::MIN_POSITIVE);
        }
        self.lag.advance(time, temperature, variance)
    }

    /// Use fitted g and τ (from [`crate::thermal_growth_fit`]) with their covariance, and a lag
    /// state recomputed with the new τ over the same readings.
    pub fn use_fitted(
        &mut self,
        coefficient: f64,
        time_constant: f64,
        covariance: Matrix2<f64>,
        lag: FirstOrderLag,
    ) -> Result<(), ThermalError> {
        if self.spec.time_constant.is_none() {
            return Err(bad(
                &format!("{}: time_constant", self.spec.sensor),
                "the online fit needs a lagged growth term".into(),
            ));
        }
        self.term = catalog_term(&self.spec, coefficient, Some(time_constant))?;
        self.parameter_covariance = covariance;
        self.lag = lag;
        self.fitted = true;
        Ok(())
    }

    /// The current T_f − T_ref (K), or why there is none.
    pub fn lagged_excess(&self) -> Result<f64, ThermalError> {
        let (_, tf, _, _) = self
            .lag
            .output()
            .ok_or_else(|| ThermalError::NoReading(self.spec.sensor.clone(), "thermal_growth"))?;
        Ok(tf - self.spec.reference_temperature)
    }

    /// The displacement the catalog term predicts with the current lag state (independent of
    /// the point: a growing column moves every point alike).
    pub fn drift(&self, nominal: &Vector3<f64>) -> Result<TermDrift, ThermalError> {
        let (time, tf, dtf_dtau, var_f) = self
            .lag
            .output()
            .ok_or_else(|| ThermalError::NoReading(self.spec.sensor.clone(), "thermal_growth"))?;
        let sensor = self.spec.sensor.as_str();
        let s = if self.spec.time_constant.is_some() {
            thermal_signals(nominal, &[], &[(sensor, time, tf)])
        } else {
            thermal_signals(nominal, &[(sensor, tf)], &[])
        };
        let p = &self.term.params;
        let d = self.term.term.predict(p, &s)?.value;
        let j = self.term.term.jacobian(p, &s)?;
        let d_dg = Vector3::new(j[(0, 0)], j[(1, 0)], j[(2, 0)]);
        // ∂d/∂T_f = n̂·g (the catalog term normalises the direction; it rejected a zero one)
        let d_dtf = self.spec.direction.normalize() * p[0];
        let d_dtau = d_dtf * dtf_dtau;
        let jp = nalgebra::Matrix3x2::from_columns(&[d_dg, d_dtau]);
        let key = if self.spec.time_constant.is_some() {
            format!("{sensor}~lag")
        } else {
            sensor.to_string()
        };
        Ok(TermDrift {
            displacement: Vector3::new(d[0], d[1], d[2]),
            temperatures: vec![TemperatureSensitivity {
                input: key,
                d_drift_d_temperature: d_dtf,
                variance: var_f + self.spec.calibration_uncertainty.powi(2),
            }],
            parameter_covariance: jp * self.parameter_covariance * jp.transpose(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_physics::{TemperatureHistory, TemperatureTimeline};

    fn column(lag: Option<f64>) -> GrowthSpec {
        GrowthSpec {
            sensor: "column".into(),
            direction: Vector3::new(0.0, 0.0, -1.0),
            coefficient: 4e-6,
            coefficient_uncertainty: 0.2e-6,
            time_constant: lag,
            time_constant_uncertainty: 60.0,
            reference_temperature: 20.0,
            calibration_uncertainty: 0.05,
        }
    }

    #[test]
    fn equals_the_catalog_term_on_the_whole_history() {
        // The incremental lag + catalog term on T_f equals the catalog term given the whole history.
        let history: Vec<(f64, f64)> = (0..2000)
            .map(|k| {
                (
                    k as f64 * 5.0,
                    20.0 + 3.0 * (1.0 - (-(k as f64) / 400.0).exp()),
                )
            })
            .collect();
        let mut g = GrowthCompensator::new(column(Some(1200.0))).unwrap();
        for (t, v) in &history {
            g.observe(*t, *v, 0.0);
        }
        let d = g.drift(&Vector3::zeros()).unwrap();
        let cfg = catalog_term(&column(Some(1200.0)), 4e-6, Some(1200.0)).unwrap();
        let s = metrocell_physics::Signals {
            timeline: Some(std::sync::Arc::new(
                TemperatureTimeline::from_histories([(
                    "column",
                    &TemperatureHistory {
                        samples: history.clone(),
                    },
                )])
                .unwrap(),
            )),
            ..Default::default()
        };
        let whole = cfg.term.predict(&cfg.params, &s).unwrap().value;
        assert!(
            (d.displacement.z - whole[2]).abs() < 1e-15,
            "{} vs {}",
            d.displacement.z,
            whole[2]
        );
        assert!(
            d.displacement.z < -10e-6,
            "a 3 K rise pushes the spindle down by ~12 µm: {}",
            d.displacement.z
        );
        // parameter covariance: u(g)·(T_f − T_ref) and u(τ)·g·∂T_f/∂τ along z, ∂T_f/∂τ from the catalog
        let (tf, dtf_dtau) = metrocell_physics::thermal::thermal_growth::first_order_lag(
            &TemperatureHistory {
                samples: history.clone(),
            },
            1200.0,
        );
        let expect = (0.2e-6 * (tf - 20.0)).powi(2) + (60.0 * 4e-6 * dtf_dtau).powi(2);
        assert!(
            (d.parameter_covariance[(2, 2)] - expect).abs() < 1e-9 * expect,
            "{} vs {expect}",
            d.parameter_covariance[(2, 2)]
        );
        // the reading input: calibration uncertainty (0.05 K) added unfiltered to T_f's variance
        assert_eq!(d.temperatures[0].input, "column~lag");
        assert!((d.temperatures[0].variance - 0.0025).abs() < 1e-15);
        assert!((d.temperatures[0].d_drift_d_temperature.z + 4e-6).abs() < 1e-20);
    }

    #[test]
    fn without_lag_it_reads_the_latest_value() {
        let mut g = GrowthCompensator::new(column(None)).unwrap();
        g.observe(0.0, 30.0, 0.0);
        g.observe(1.0, 22.0, 0.01);
        let d = g.drift(&Vector3::zeros()).unwrap();
        assert!((d.displacement.z + 8e-6).abs() < 1e-18);
        assert!((d.temperatures[0].variance - (0.01 + 0.0025)).abs() < 1e-15);
    }

    #[test]
    fn bad_parameters_are_named() {
        let mut s = column(Some(1200.0));
        s.coefficient = 1.0;
        let e = GrowthCompensator::new(s).unwrap_err().to_string();
        assert!(
            e.contains("coefficient") && e.contains("thermal_growth[column]"),
            "{e}"
        );
        // a negative lag is impossible (a lag of 0.1 s is merely short)
        let mut s = column(Some(-5.0));
        s.time_constant_uncertainty = 1.0;
        let e = GrowthCompensator::new(s).unwrap_err().to_string();
        assert!(e.contains("time_constant"), "{e}");
        let mut s = column(None);
        s.calibration_uncertainty = f64::NAN;
        assert!(GrowthCompensator::new(s)
            .unwrap_err()
            .to_string()
            .contains("column: calibration_uncertainty"));
        assert_eq!(
            GrowthCompensator::new(column(None))
                .unwrap()
                .drift(&Vector3::zeros())
                .unwrap_err(),
            ThermalError::NoReading("column".into(), "thermal_growth")
        );
    }
}
