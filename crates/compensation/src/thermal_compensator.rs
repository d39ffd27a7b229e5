//! Every configured thermal term together: axis scales, structure growth (lagged), workpiece
//! expansion. One point's drift is the sum of the terms' displacements, its covariance is
//! combined by [`total_drift`] (a sensor read by two terms is one input).

use std::collections::BTreeSet;

use nalgebra::{Matrix3, Vector3};

use crate::thermal_drift::{total_drift, TermDrift};
use crate::thermal_error::{Reading, ThermalError};
use crate::thermal_growth_compensation::GrowthCompensator;
use crate::thermal_scale_compensation::ThermalScaleCompensator;
use crate::thermal_workpiece_compensation::WorkpieceCompensator;

#[derive(Debug)]
pub struct ThermalCompensator {
    pub scale: ThermalScaleCompensator,
    pub growth: Vec<GrowthCompensator>,
    pub workpiece: Option<WorkpieceCompensator>,
}

impl ThermalCompensator {
    /// Every sensor any term reads, each once, sorted. A correction needs a fresh reading of each
    /// (the lagged growth terms carry their own state, but their sensor must still be reporting).
    pub fn sensor_names(&self) -> Vec<String> {
        let mut s: BTreeSet<String> = self
            .scale
            .sensors()
            .iter()
            .map(|p| p.name.clone())
            .collect();
        s.extend(self.growth.iter().map(|g| g.spec.sensor.clone()));
        s.extend(self.workpiece.iter().map(|w| w.sensor.clone()));
        s.into_iter().collect()
    }

    /// Feed a reading (°C, K²) of `sensor` at `time` (s) to every lagged term that reads it.
    pub fn observe(&mut self, sensor: &str, time: f64, temperature: f64, variance: f64) {
        for g in self.growth.iter_mut().filter(|g| g.spec.sensor == sensor) {
            g.observe(time, temperature, variance);
        }
    }

    /// The drift at `nominal` (see [`crate::thermal_drift`] for the convention) and its covariance.
    pub fn drift(
        &self,
        nominal: &Vector3<f64>,
        reading: &dyn Fn(&str) -> Option<Reading>,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ThermalError> {
        if !nominal.iter().all(|v| v.is_finite()) {
            return Err(ThermalError::NotFinite {
                what: "nominal point".into(),
            });
        }
        let mut terms: Vec<TermDrift> = self.scale.drift(nominal, reading)?;
        for g in &self.growth {
            terms.push(g.drift(nominal)?);
        }
        if let Some(w) = &self.workpiece {
            let r = reading(&w.sensor)
                .ok_or_else(|| ThermalError::NoReading(w.sensor.clone(), "workpiece_expansion"))?;
            terms.push(w.drift(nominal, r)?);
        }
        Ok(total_drift(&terms))
    }

    /// `measured` with the drift at `nominal` removed, covariance enlarged by the drift's.
    pub fn compensate(
        &self,
        nominal: &Vector3<f64>,
        measured: &Vector3<f64>,
        cov: &Matrix3<f64>,
        reading: &dyn Fn(&str) -> Option<Reading>,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ThermalError> {
        if !measured.iter().all(|v| v.is_finite()) || !cov.iter().all(|v| v.is_finite()) {
            return Err(ThermalError::NotFinite {
                what: "measured point or its covariance".into(),
            });
        }
        let (d, d_cov) = self.drift(nominal, reading)?;
        Ok((measured - d, cov + d_cov))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal_growth_compensation::GrowthSpec;
    use crate::thermal_scale_compensation::AxisSensorPlacement;
    use metrocell_physics::thermal::cte_uncertainty::cte_standard_uncertainty;

    fn compensator(u_alpha: f64) -> ThermalCompensator {
        let scale = ThermalScaleCompensator::new(
            11.5e-6,
            u_alpha,
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
                    position: 0.8,
                },
            ],
        )
        .unwrap();
        let growth = GrowthCompensator::new(GrowthSpec {
            sensor: "column".into(),
            direction: Vector3::new(0.0, 0.0, -1.0),
            coefficient: 4e-6,
            coefficient_uncertainty: 0.0,
            time_constant: None,
            time_constant_uncertainty: 0.0,
            reference_temperature: 20.0,
            calibration_uncertainty: 0.0,
        })
        .unwrap();
        ThermalCompensator {
            scale,
            growth: vec![growth],
            workpiece: None,
        }
    }

    fn readings(n: &str) -> Option<Reading> {
        match n {
            "x_left" | "x_right" => Some((21.0, 0.0)),
            "column" => Some((22.0, 0.0)),
            _ => None,
        }
    }

    #[test]
    fn sums_scale_and_growth() {
        let mut c = compensator(0.0);
        c.observe("column", 0.0, 22.0, 0.0);
        let (d, _) = c.drift(&Vector3::new(0.5, 0.1, 0.2), &readings).unwrap();
        assert!((d.x - 11.5e-6 * 0.5 * 1.0).abs() < 1e-18);
        assert_eq!(d.y, 0.0);
        assert!((d.z + 8e-6).abs() < 1e-18);
        assert_eq!(c.sensor_names(), ["column", "x_left", "x_right"]);
    }

    #[test]
    fn thesis_u_alpha_gives_0_0006_um_per_mm_and_kelvin() {
        // u(α) = 0.002/(2√3) µm/(mm·K) (ISO/TR 230-9, thesis P5 eq. 10) for a steel scale: a point
        // 1000 mm along X at 1 K above 20 °C carries σ_x = 0.0006 µm/(mm·K)·1000 mm·1 K = 0.6 µm.
        let mut c = compensator(cte_standard_uncertainty(11.5e-6));
        c.observe("column", 0.0, 22.0, 0.0);
        let (_, cov) = c.drift(&Vector3::new(1.0, 0.0, 0.0), &readings).unwrap();
        let sigma_um_per_mm_k = cov[(0, 0)].sqrt() * 1e6 / 1000.0 / 1.0;
        assert_eq!(format!("{sigma_um_per_mm_k:.4}"), "0.0006");
        assert!((sigma_um_per_mm_k - 0.000577).abs() < 1e-6);
    }

    #[test]
    fn missing_and_bad_inputs_are_named() {
        let c = compensator(0.0);
        assert_eq!(
            c.drift(&Vector3::zeros(), &readings).unwrap_err(),
            ThermalError::NoReading("column".into(), "thermal_growth")
        );
        let e = c
            .compensate(
                &Vector3::zeros(),
                &Vector3::new(f64::NAN, 0.0, 0.0),
                &Matrix3::zeros(),
                &readings,
            )
            .unwrap_err();
        assert_eq!(e.reason(), "not_finite");
        let e = c
            .drift(&Vector3::new(0.1, 0.0, 0.0), &|n| {
                (n != "x_right").then_some((21.0, 0.0))
            })
            .unwrap_err();
        assert_eq!(e, ThermalError::NoReading("x_right".into(), "x"));
    }
}
