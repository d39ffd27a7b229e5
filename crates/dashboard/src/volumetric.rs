//! Volumetric error of one stream of measured points: e = measured − nominal per axis [m]
//! (machine frame as the points carry it; positive when the machine went past the nominal),
//! its drift rate per axis, and the predicted error now.
//!
//! "Predicted" is the drift line's value at the newest stamp: the error the machine would show
//! at a point measured now, with the scatter of the window averaged out. Before the window holds
//! 3 points it falls back to the newest error and the instrument's σ from the point's covariance.

use metrocell_msgs::msg::MeasuredPoint;
use serde::Serialize;

use crate::series::{PlotData, Series};
use crate::trend::Trend;
use crate::InputError;

pub const AXES: [&str; 3] = ["x", "y", "z"];

#[derive(Clone, Debug)]
pub struct VolumetricError {
    axes: [Series; 3],
    /// Newest point: stamp [s], error [m], σ from its covariance [m].
    latest: Option<(f64, [f64; 3], [f64; 3])>,
    count: u64,
}

/// One axis, SI: m and m/s.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisSummary {
    pub axis: &'static str,
    /// Newest error [m] and its instrument σ [m].
    pub latest: f64,
    pub latest_sigma: f64,
    /// Predicted error now [m] ± σ.
    pub predicted: f64,
    pub predicted_sigma: f64,
    /// Drift rate [m/s] ± σ; absent until the window holds 3 points at 2 times.
    pub drift: Option<f64>,
    pub drift_sigma: Option<f64>,
    pub plot: PlotData,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VolumetricSummary {
    /// Points received since start.
    pub count: u64,
    /// Stamp of the newest point [s since the epoch].
    pub stamp: f64,
    pub axes: Vec<AxisSummary>,
    /// |predicted error vector| [m] ± σ.
    pub magnitude: f64,
    pub magnitude_sigma: f64,
    /// Largest |drift| of the axes [m/s] with its σ, and its axis.
    pub max_drift: Option<(f64, f64, &'static str)>,
    /// Window the drift is fitted over [s].
    pub window_span: f64,
}

fn finite(field: &str, v: f64) -> Result<f64, InputError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(InputError::new(field, format!("is {v}")))
    }
}

impl VolumetricError {
    pub fn new(window: f64, max_samples: usize) -> VolumetricError {
        let s = Series::new(window, max_samples);
        VolumetricError {
            axes: [s.clone(), s.clone(), s],
            latest: None,
            count: 0,
        }
    }

    /// Add a point; a NaN/inf coordinate or a negative variance is rejected naming the field.
    pub fn push(&mut self, p: &MeasuredPoint) -> Result<(), InputError> {
        let t = crate::stamp_seconds(&p.header.stamp);
        let nominal = [
            finite("nominal.x", p.nominal.x)?,
            finite("nominal.y", p.nominal.y)?,
            finite("nominal.z", p.nominal.z)?,
        ];
        let measured = [
            finite("measured.x", p.measured.x)?,
            finite("measured.y", p.measured.y)?,
            finite("measured.z", p.measured.z)?,
        ];
        let mut sigma = [0.0; 3];
        for (k, s) in sigma.iter_mut().enumerate() {
            let var = finite(&format!("covariance[{}]", 4 * k), p.covariance[4 * k])?;
            if var < 0.0 {
                return Err(InputError::new(
                    &format!("covariance[{}]", 4 * k),
                    format!("is a negative variance {var}"),
                ));
            }
            *s = var.sqrt();
        }
        let e = [
            measured[0] - nominal[0],
            measured[1] - nominal[1],
            measured[2] - nominal[2],
        ];
        for (k, series) in self.axes.iter_mut().enumerate() {
            series.push(t, e[k]);
        }
        if self.latest.is_none_or(|(t0, _, _)| t >= t0) {
            self.latest = Some((t, e, sigma));
        }
        self.count += 1;
        Ok(())
    }

    pub fn count(&self) -> u64 {
        self.count
    }

    pub fn summary(&self, max_plot_points: usize) -> Option<VolumetricSummary> {
        let (stamp, latest, latest_sigma) = self.latest?;
        let mut axes = Vec::new();
        let mut span: f64 = 0.0;
        for (k, s) in self.axes.iter().enumerate() {
            let trend: Option<Trend> = s.trend();
            span = span.max(trend.map_or(0.0, |t| t.span));
            let (predicted, predicted_sigma) = match trend {
                Some(t) => (
                    t.value,
                    t.value_sigma
                        .max(latest_sigma[k] / (t.samples as f64).sqrt()),
                ),
                None => (latest[k], latest_sigma[k]),
            };
            axes.push(AxisSummary {
                axis: AXES[k],
                latest: latest[k],
                latest_sigma: latest_sigma[k],
                predicted,
                predicted_sigma,
                drift: trend.map(|t| t.rate),
                drift_sigma: trend.map(|t| t.rate_sigma),
                plot: s.plot(stamp, max_plot_points),
            });
        }
        let magnitude = axes
            .iter()
            .map(|a| a.predicted * a.predicted)
            .sum::<f64>()
            .sqrt();
        // first-order propagation of the axis σ through |e|; at |e| = 0 the largest axis σ
        let magnitude_sigma = if magnitude > 0.0 {
            axes.iter()
                .map(|a| (a.predicted / magnitude * a.predicted_sigma).powi(2))
                .sum::<f64>()
                .sqrt()
        } else {
            axes.iter().map(|a| a.predicted_sigma).fold(0.0, f64::max)
        };
        let max_drift = axes
            .iter()
            .filter_map(|a| Some((a.drift?, a.drift_sigma?, a.axis)))
            .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        Some(VolumetricSummary {
            count: self.count,
            stamp,
            axes,
            magnitude,
            magnitude_sigma,
            max_drift,
            window_span: span,
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use metrocell_msgs::builtin_interfaces::msg::Time;

    pub(crate) fn point(t: f64, nominal: [f64; 3], error: [f64; 3]) -> MeasuredPoint {
        let mut p = MeasuredPoint::default();
        p.header.stamp = Time::from_nanos((t * 1e9).round() as i64);
        (p.nominal.x, p.nominal.y, p.nominal.z) = (nominal[0], nominal[1], nominal[2]);
        (p.measured.x, p.measured.y, p.measured.z) = (
            nominal[0] + error[0],
            nominal[1] + error[1],
            nominal[2] + error[2],
        );
        p.covariance = [1e-12, 0.0, 0.0, 0.0, 1e-12, 0.0, 0.0, 0.0, 4e-12];
        p
    }

    #[test]
    fn synthetic_ramp_gives_drift_per_axis_and_predicted_magnitude() {
        // x drifts +36 µm/h from 2 µm, y is constant −3 µm, z drifts −18 µm/h; one point a minute for an hour
        let mut v = VolumetricError::new(7200.0, 10_000);
        let t0 = 1_750_000_000.0;
        for k in 0..=60 {
            let h = k as f64 / 60.0;
            v.push(&point(
                t0 + 60.0 * k as f64,
                [0.1 * k as f64, 0.2, 0.3],
                [2e-6 + 36e-6 * h, -3e-6, -18e-6 * h],
            ))
            .unwrap();
        }
        let s = v.summary(50).unwrap();
        let per_hour: Vec<f64> = s
            .axes
            .iter()
            .map(|a| a.drift.unwrap() * 3600.0 * 1e6)
            .collect();
        assert!(
            (per_hour[0] - 36.0).abs() < 1e-6
                && per_hour[1].abs() < 1e-6
                && (per_hour[2] + 18.0).abs() < 1e-6,
            "{per_hour:?} µm/h"
        );
        // at the end: (38, −3, −18) µm → |e| = √(38² + 3² + 18²) µm
        let expected = (38f64.powi(2) + 9.0 + 18f64.powi(2)).sqrt() * 1e-6;
        assert!(
            (s.magnitude - expected).abs() < 1e-12,
            "{} vs {expected}",
            s.magnitude
        );
        let (d, _, axis) = s.max_drift.unwrap();
        assert_eq!(axis, "x");
        assert!((d * 3600.0 - 36e-6).abs() < 1e-12);
        assert_eq!((s.count, s.window_span), (61, 3600.0));
        // a perfect line has no scatter: the σ floor is the instrument σ averaged over the window
        assert!((s.axes[2].predicted_sigma - 2e-6 / 61f64.sqrt()).abs() < 1e-12);
        assert_eq!(s.axes[0].plot.v.len(), 31);
    }

    #[test]
    fn first_point_uses_its_covariance_and_bad_points_name_the_field() {
        let mut v = VolumetricError::new(60.0, 100);
        v.push(&point(10.0, [0.0; 3], [3e-6, 4e-6, 0.0])).unwrap();
        let s = v.summary(10).unwrap();
        assert!((s.magnitude - 5e-6).abs() < 1e-15);
        // σ|e| = √((3/5·1µm)² + (4/5·1µm)²) = 1 µm
        assert!((s.magnitude_sigma - 1e-6).abs() < 1e-15);
        assert!(s.max_drift.is_none());
        let mut bad = point(11.0, [0.0; 3], [0.0; 3]);
        bad.measured.y = f64::NAN;
        assert_eq!(v.push(&bad).unwrap_err().to_string(), "measured.y is NaN");
        let mut neg = point(11.0, [0.0; 3], [0.0; 3]);
        neg.covariance[8] = -1.0;
        assert!(v
            .push(&neg)
            .unwrap_err()
            .to_string()
            .starts_with("covariance[8] is a negative variance"));
        assert_eq!(v.count(), 1);
    }
}
