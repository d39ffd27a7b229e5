//! The node's logic with time passed in (`now_ns`): live it is the node clock, on a bag it is
//! the bag's log time, so a replay makes the same decisions (staleness, model period) as the
//! live run that was recorded.

use std::collections::BTreeMap;

use metrocell_compensation::{ThermalError, ThermalScaleCompensator};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use nalgebra::{Matrix3, Vector3};

pub struct ThermalState {
    pub compensator: ThermalScaleCompensator,
    period_ns: i64,
    stale_after_ns: i64,
    /// sensor → (temperature °C, variance K², receive time ns)
    latest: BTreeMap<String, (f64, f64, i64)>,
    next_model_ns: Option<i64>,
}

impl ThermalState {
    pub fn new(compensator: ThermalScaleCompensator, period_s: f64, stale_after_s: f64) -> Self {
        Self {
            compensator,
            period_ns: (period_s * 1e9).round() as i64,
            stale_after_ns: (stale_after_s * 1e9).round() as i64,
            latest: BTreeMap::new(),
            next_model_ns: None,
        }
    }

    /// Store a reading; `Err` names why it was rejected.
    pub fn temperature(&mut self, sensor: &str, t: &Temperature, now_ns: i64) -> Result<(), String> {
        if t.temperature.is_finite() && t.variance.is_finite() && t.variance >= 0.0 {
            self.latest.insert(sensor.to_string(), (t.temperature, t.variance, now_ns));
            Ok(())
        } else {
            Err(format!("temperature/{sensor}: rejected reading {} °C (variance {})", t.temperature, t.variance))
        }
    }

    fn reading(&self, name: &str, now_ns: i64) -> Option<(f64, f64)> {
        self.latest.get(name).filter(|r| now_ns - r.2 <= self.stale_after_ns).map(|r| (r.0, r.1))
    }

    /// The point with the thermal growth removed and its covariance enlarged.
    pub fn compensate(&self, p: &MeasuredPoint, now_ns: i64) -> Result<MeasuredPoint, ThermalError> {
        let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
        let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
        let cov = Matrix3::from_row_slice(&p.covariance);
        let (c, c_cov) = self.compensator.compensate(&nominal, &measured, &cov, &|n: &str| self.reading(n, now_ns))?;
        let mut out = p.clone();
        (out.measured.x, out.measured.y, out.measured.z) = (c.x, c.y, c.z);
        out.covariance.copy_from_slice(c_cov.transpose().as_slice());
        Ok(out)
    }

    /// The error model when one is due at `now_ns` (first call, then every period).
    pub fn model_if_due(&mut self, now_ns: i64) -> Option<Result<ErrorModel, ThermalError>> {
        let due = self.next_model_ns.map_or(true, |t| now_ns >= t);
        if !due {
            return None;
        }
        // next = previous deadline + period; after a gap longer than a period (e.g. in a bag)
        // restart from now instead of publishing a burst.
        let next = self.next_model_ns.unwrap_or(now_ns) + self.period_ns;
        self.next_model_ns = Some(if next <= now_ns { now_ns + self.period_ns } else { next });
        Some(crate::parameters::error_model(&self.compensator, &|n: &str| self.reading(n, now_ns), now_ns))
    }
}
