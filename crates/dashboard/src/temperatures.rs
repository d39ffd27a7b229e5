//! Temperatures by sensor (`temperature/<sensor>`, °C as sensor_msgs/Temperature carries them):
//! the newest reading with its σ, the drift over the window, and a plot.

use std::collections::BTreeMap;

use metrocell_msgs::sensor_msgs::msg::Temperature;
use serde::Serialize;

use crate::series::{PlotData, Series};
use crate::InputError;

#[derive(Clone, Debug)]
pub struct Temperatures {
    window: f64,
    max_samples: usize,
    sensors: BTreeMap<String, (Series, f64)>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SensorSummary {
    pub sensor: String,
    /// [°C] ± σ [K] (the message's variance).
    pub value: f64,
    pub sigma: f64,
    /// Stamp of the newest reading [s since the epoch].
    pub stamp: f64,
    /// [K/s] ± σ over the window.
    pub rate: Option<f64>,
    pub rate_sigma: Option<f64>,
    pub plot: PlotData,
}

impl Temperatures {
    pub fn new(window: f64, max_samples: usize) -> Temperatures {
        Temperatures {
            window,
            max_samples,
            sensors: BTreeMap::new(),
        }
    }

    pub fn push(&mut self, sensor: &str, t: &Temperature) -> Result<(), InputError> {
        if !t.temperature.is_finite() {
            return Err(InputError::new(
                "temperature",
                format!("is {}", t.temperature),
            ));
        }
        if !(t.variance.is_finite() && t.variance >= 0.0) {
            return Err(InputError::new(
                "variance",
                format!("is {} (must be a finite variance ≥ 0)", t.variance),
            ));
        }
        let (series, var) = self
            .sensors
            .entry(sensor.to_string())
            .or_insert_with(|| (Series::new(self.window, self.max_samples), 0.0));
        series.push(crate::stamp_seconds(&t.header.stamp), t.temperature);
        *var = t.variance;
        Ok(())
    }

    pub fn summary(&self, max_plot_points: usize) -> Vec<SensorSummary> {
        self.sensors
            .iter()
            .filter_map(|(name, (series, var))| {
                let (stamp, value) = series.latest()?;
                let trend = series.trend();
                Some(SensorSummary {
                    sensor: name.clone(),
                    value,
                    sigma: var.sqrt(),
                    stamp,
                    rate: trend.map(|t| t.rate),
                    rate_sigma: trend.map(|t| t.rate_sigma),
                    plot: series.plot(stamp, max_plot_points),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_msgs::builtin_interfaces::msg::Time;

    fn reading(t: f64, v: f64, var: f64) -> Temperature {
        let mut m = Temperature {
            temperature: v,
            variance: var,
            ..Default::default()
        };
        m.header.stamp = Time::from_nanos((t * 1e9) as i64);
        m
    }

    #[test]
    fn sensors_are_listed_by_name_with_rate_and_sigma() {
        let mut ts = Temperatures::new(600.0, 1000);
        for k in 0..10 {
            ts.push(
                "x_right",
                &reading(k as f64, 21.0 + 0.01 * k as f64, 0.0004),
            )
            .unwrap();
            ts.push("x_left", &reading(k as f64, 20.5, 0.0001)).unwrap();
        }
        let s = ts.summary(100);
        assert_eq!(
            s.iter().map(|s| s.sensor.as_str()).collect::<Vec<_>>(),
            ["x_left", "x_right"]
        );
        assert!((s[1].value - 21.09).abs() < 1e-12 && (s[1].sigma - 0.02).abs() < 1e-15);
        assert!((s[1].rate.unwrap() - 0.01).abs() < 1e-12);
        assert_eq!(s[0].rate, Some(0.0));
    }

    #[test]
    fn bad_readings_name_the_field() {
        let mut ts = Temperatures::new(600.0, 1000);
        assert_eq!(
            ts.push("a", &reading(0.0, f64::NAN, 0.0))
                .unwrap_err()
                .to_string(),
            "temperature is NaN"
        );
        assert!(ts
            .push("a", &reading(0.0, 20.0, -1.0))
            .unwrap_err()
            .to_string()
            .starts_with("variance is -1"));
        assert!(ts.summary(10).is_empty());
    }
}
