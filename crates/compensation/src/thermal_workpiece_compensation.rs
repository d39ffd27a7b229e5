//! Referring a measured workpiece or artefact back to 20 °C: the catalog's
//! `workpiece_expansion` term, d = α·(T_w − T_ref)·(p − c), expansion about the clamp point c,
//! evaluated at the feature's nominal position p. The workpiece frame is taken parallel to the
//! machine frame (points arrive in the machine frame). Subtracting d from a point measured at
//! T_w is the thesis's plate correction d_f = d₀·(1 − α·(T − 20 °C)) to first order.

use metrocell_physics::{configure, ConfigValue, ConfiguredTerm, TermConfig};
use nalgebra::Vector3;

use crate::thermal_drift::{TemperatureSensitivity, TermDrift};
use crate::thermal_error::{Reading, ThermalError};
use crate::thermal_signals::thermal_signals;

#[derive(Debug)]
pub struct WorkpieceCompensator {
    pub sensor: String,
    pub clamp: Vector3<f64>,
    /// 1/K
    pub alpha: f64,
    /// u(α), 1/K
    pub alpha_uncertainty: f64,
    /// °C
    pub reference_temperature: f64,
    term: ConfiguredTerm,
}

impl WorkpieceCompensator {
    pub fn new(
        sensor: &str,
        clamp: Vector3<f64>,
        alpha: f64,
        alpha_uncertainty: f64,
        reference_temperature: f64,
    ) -> Result<Self, ThermalError> {
        if !(alpha_uncertainty >= 0.0 && alpha_uncertainty.is_finite()) {
            return Err(ThermalError::BadParameter {
                name: "workpiece_alpha_uncertainty".into(),
                reason: format!("must be ≥ 0 and finite, got {alpha_uncertainty}"),
            });
        }
        let n = ConfigValue::Number;
        let term = configure(&TermConfig {
            id: "workpiece_expansion".into(),
            options: [
                ("sensor".to_string(), ConfigValue::Text(sensor.into())),
                (
                    "clamp".to_string(),
                    ConfigValue::List(vec![n(clamp.x), n(clamp.y), n(clamp.z)]),
                ),
                (
                    "reference_temperature".to_string(),
                    n(reference_temperature),
                ),
            ]
            .into_iter()
            .collect(),
            params: [("alpha".to_string(), n(alpha))].into_iter().collect(),
            use_defaults: false,
        })?;
        Ok(Self {
            sensor: sensor.into(),
            clamp,
            alpha,
            alpha_uncertainty,
            reference_temperature,
            term,
        })
    }

    /// Catalog label, e.g. `workpiece_expansion[plate]`.
    pub fn label(&self) -> String {
        self.term.term.label()
    }

    /// The catalog term in use (options, parameter values).
    pub fn catalog_term(&self) -> &ConfiguredTerm {
        &self.term
    }

    /// The expansion at `nominal` for the workpiece sensor's reading (its variance is the whole
    /// variance of the reading, calibration included).
    pub fn drift(
        &self,
        nominal: &Vector3<f64>,
        reading: Reading,
    ) -> Result<TermDrift, ThermalError> {
        let (t, var) = reading;
        if !(t.is_finite() && var.is_finite()) {
            return Err(ThermalError::NotFinite {
                what: format!("reading of sensor '{}'", self.sensor),
            });
        }
        let p = &self.term.params;
        let s = thermal_signals(nominal, &[(&self.sensor, t)], &[]);
        let d = self.term.term.predict(p, &s)?.value;
        let j = self.term.term.jacobian(p, &s)?;
        let lever = Vector3::new(j[(0, 0)], j[(1, 0)], j[(2, 0)]);
        // linear in T: at T_ref + 1 K the term returns ∂d/∂T = α·(p − c)
        let v = self
            .term
            .term
            .predict(
                p,
                &thermal_signals(
                    nominal,
                    &[(&self.sensor, self.reference_temperature + 1.0)],
                    &[],
                ),
            )?
            .value;
        Ok(TermDrift {
            displacement: Vector3::new(d[0], d[1], d[2]),
            temperatures: vec![TemperatureSensitivity {
                input: self.sensor.clone(),
                d_drift_d_temperature: Vector3::new(v[0], v[1], v[2]),
                variance: var,
            }],
            parameter_covariance: lever * lever.transpose() * self.alpha_uncertainty.powi(2),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_physics::thermal::cte_uncertainty::cte_standard_uncertainty;
    use metrocell_physics::thermal::workpiece_expansion::corrected_distance;

    #[test]
    fn thesis_plate_300_mm_at_21_degc_is_299_9928_mm() {
        // P2 fixture: d₀ = 300 mm measured at 21 °C, α = 24e-6 /K → 299.9928 mm at 20 °C
        let w = WorkpieceCompensator::new(
            "plate",
            Vector3::zeros(),
            24e-6,
            cte_standard_uncertainty(24e-6),
            20.0,
        )
        .unwrap();
        let nominal = Vector3::new(0.3, 0.0, 0.0);
        let d = w.drift(&nominal, (21.0, 0.0)).unwrap();
        let corrected_mm = (0.3 - d.displacement.x) * 1e3;
        assert_eq!(format!("{corrected_mm:.4}"), "299.9928");
        assert!((corrected_mm - corrected_distance(300.0, 24e-6, 21.0, 20.0)).abs() < 1e-12);
        assert_eq!(d.displacement.y, 0.0);
    }

    #[test]
    fn expansion_is_about_the_clamp_and_carries_u_alpha() {
        // clamp at (200, 250) mm as in the thesis plate; a feature 100 mm further in x at 22 °C
        let w = WorkpieceCompensator::new("plate", Vector3::new(0.2, 0.25, 0.0), 24e-6, 1e-6, 20.0)
            .unwrap();
        let d = w
            .drift(&Vector3::new(0.3, 0.25, 0.0), (22.0, 0.02))
            .unwrap();
        assert!((d.displacement.x - 24e-6 * 2.0 * 0.1).abs() < 1e-18);
        assert!(
            d.displacement.y.abs() < 1e-18,
            "no expansion at the clamp's y"
        );
        assert!((d.parameter_covariance[(0, 0)] - (0.1f64 * 2.0 * 1e-6).powi(2)).abs() < 1e-24);
        assert!((d.temperatures[0].d_drift_d_temperature.x - 24e-6 * 0.1).abs() < 1e-18);
        assert!(
            (d.temperatures[0].variance - 0.02).abs() < 1e-15,
            "the reading's variance"
        );
        assert!(matches!(
            w.drift(&Vector3::zeros(), (f64::NAN, 0.0)),
            Err(ThermalError::NotFinite { .. })
        ));
    }

    #[test]
    fn alpha_outside_the_catalog_range_names_the_parameter() {
        let e = WorkpieceCompensator::new("plate", Vector3::zeros(), 1e-3, 0.0, 20.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("workpiece_expansion[plate]") && e.contains("alpha"),
            "{e}"
        );
    }
}
