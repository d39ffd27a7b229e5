//! The predicted thermal displacement of one point and where its uncertainty comes from, summed
//! over terms.
//!
//! Convention: the drift is the displacement the terms predict (realised minus commanded, tool
//! relative to workpiece, machine frame; the workpiece frame is taken parallel to it), so a
//! measured point is corrected by subtracting it. Its covariance is
//! Σ_sensors v_s·v_sᵀ·var_s + Σ_terms J_p·Σ_p·J_pᵀ, v_s = ∂d/∂T_s summed over every term that
//! reads sensor s (so a sensor shared by two terms is counted as one correlated input).

use std::collections::BTreeMap;

use nalgebra::{Matrix3, Vector3};

/// One temperature input of the drift: ∂d/∂T (m/K) and the variance of T (K²).
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureSensitivity {
    /// Sensor name; a lagged sensor is keyed `name~lag` (its T_f is a different input).
    pub input: String,
    pub d_drift_d_temperature: Vector3<f64>,
    pub variance: f64,
}

/// What one term contributes.
#[derive(Debug, Clone, PartialEq)]
pub struct TermDrift {
    pub displacement: Vector3<f64>,
    pub temperatures: Vec<TemperatureSensitivity>,
    /// J_p·Σ_p·J_pᵀ of the term's parameters (m²).
    pub parameter_covariance: Matrix3<f64>,
}

/// Sum of terms: the drift and its covariance.
pub fn total_drift(terms: &[TermDrift]) -> (Vector3<f64>, Matrix3<f64>) {
    let mut d = Vector3::zeros();
    let mut cov = Matrix3::zeros();
    let mut by_input: BTreeMap<&str, (Vector3<f64>, f64)> = BTreeMap::new();
    for t in terms {
        d += t.displacement;
        cov += t.parameter_covariance;
        for s in &t.temperatures {
            let e = by_input
                .entry(s.input.as_str())
                .or_insert((Vector3::zeros(), s.variance));
            e.0 += s.d_drift_d_temperature;
        }
    }
    for (v, var) in by_input.values() {
        cov += v * v.transpose() * *var;
    }
    (d, cov)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_sensor_adds_its_sensitivities_before_squaring() {
        let s = |v: f64| TemperatureSensitivity {
            input: "t".into(),
            d_drift_d_temperature: Vector3::new(v, 0.0, 0.0),
            variance: 4.0,
        };
        let a = TermDrift {
            displacement: Vector3::new(1.0, 0.0, 0.0),
            temperatures: vec![s(1.0)],
            parameter_covariance: Matrix3::identity(),
        };
        let b = TermDrift {
            displacement: Vector3::new(0.0, 2.0, 0.0),
            temperatures: vec![s(2.0)],
            parameter_covariance: Matrix3::zeros(),
        };
        let (d, cov) = total_drift(&[a, b]);
        assert_eq!(d, Vector3::new(1.0, 2.0, 0.0));
        // (1 + 2)²·4 + 1, not (1² + 2²)·4 + 1
        assert_eq!(cov[(0, 0)], 37.0);
        assert_eq!(cov[(1, 1)], 1.0);
    }
}
