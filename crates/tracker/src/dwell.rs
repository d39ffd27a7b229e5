//! Dwells: the consecutive readings of one named target while the machine stands still,
//! averaged into one point with its standard error.
//!
//! A dwell ends when the target name changes (an empty name means the target is moving), or
//! when no reading of it arrived for `max_gap_ns` (the next visit of the same nest is a new
//! dwell). Beam breaks inside a dwell are simply missing readings.

use nalgebra::{Matrix3, Vector3};

use crate::reading::ProcessedReading;
use crate::turbulence::TurbulenceVerdict;

/// The average of one dwell.
#[derive(Debug, Clone, PartialEq)]
pub struct DwellAverage {
    pub target: String,
    pub first_ns: i64,
    pub last_ns: i64,
    /// number of readings averaged
    pub n: usize,
    /// tracker frame, m
    pub point: Vector3<f64>,
    pub range: f64,
    pub azimuth: f64,
    pub elevation: f64,
    /// m² — covariance of the mean by the noise model: (mean per-reading covariance)/n
    pub covariance: Matrix3<f64>,
    /// m² — covariance of the mean from the readings' own scatter (sample covariance / n)
    pub empirical_covariance: Matrix3<f64>,
    /// every range averaged (m), for the turbulence test
    pub ranges: Vec<f64>,
    /// mean index used for the ranges, and the mean air
    pub refractive_index: f64,
    pub air: metrocell_compensation::AirData,
}

impl DwellAverage {
    /// Mid time of the dwell, ns.
    pub fn mid_ns(&self) -> i64 {
        self.first_ns + (self.last_ns - self.first_ns) / 2
    }

    /// The covariance to publish: the model's, inflated by the observed/expected variance
    /// ratio when the turbulence test flagged the dwell (then the model is known to be too
    /// optimistic, and the scatter is the better estimate).
    pub fn covariance_given(&self, verdict: Option<&TurbulenceVerdict>) -> Matrix3<f64> {
        match verdict {
            Some(v) if v.flagged => self.covariance * v.scatter_ratio.powi(2).max(1.0),
            _ => self.covariance,
        }
    }
}

/// Groups processed readings into dwells.
#[derive(Debug, Clone)]
pub struct DwellGrouper {
    max_gap_ns: i64,
    open: Vec<ProcessedReading>,
}

impl DwellGrouper {
    pub fn new(max_gap_ns: i64) -> Self {
        Self {
            max_gap_ns,
            open: Vec::new(),
        }
    }

    /// Add a reading; returns the dwell it closed, if any.
    pub fn push(&mut self, r: ProcessedReading) -> Option<DwellAverage> {
        let continues = self.open.last().is_some_and(|last| {
            last.target == r.target && r.time_ns - last.time_ns <= self.max_gap_ns
        });
        let closed = if continues { None } else { self.flush() };
        if !r.target.is_empty() {
            self.open.push(r);
        }
        closed
    }

    /// A moving-target reading or a long silence at `now_ns` closes the open dwell.
    pub fn close_if_stale(&mut self, now_ns: i64) -> Option<DwellAverage> {
        match self.open.last() {
            Some(last) if now_ns - last.time_ns > self.max_gap_ns => self.flush(),
            _ => None,
        }
    }

    /// Close and return the open dwell.
    pub fn flush(&mut self) -> Option<DwellAverage> {
        let readings = std::mem::take(&mut self.open);
        average(&readings)
    }
}

/// Average of readings of one target (None when empty).
pub fn average(readings: &[ProcessedReading]) -> Option<DwellAverage> {
    let first = readings.first()?;
    let n = readings.len() as f64;
    let point = readings.iter().map(|r| r.point).sum::<Vector3<f64>>() / n;
    let model = readings.iter().map(|r| r.covariance).sum::<Matrix3<f64>>() / n;
    let scatter = if readings.len() > 1 {
        readings
            .iter()
            .map(|r| (r.point - point) * (r.point - point).transpose())
            .sum::<Matrix3<f64>>()
            / (n - 1.0)
    } else {
        Matrix3::zeros()
    };
    let mean = |f: fn(&ProcessedReading) -> f64| readings.iter().map(f).sum::<f64>() / n;
    let air = metrocell_compensation::AirData {
        temperature: mean(|r| r.air.temperature),
        pressure: mean(|r| r.air.pressure),
        humidity: mean(|r| r.air.humidity),
    };
    Some(DwellAverage {
        target: first.target.clone(),
        first_ns: first.time_ns,
        last_ns: readings[readings.len() - 1].time_ns,
        n: readings.len(),
        point,
        range: mean(|r| r.range),
        azimuth: mean(|r| r.azimuth),
        elevation: mean(|r| r.elevation),
        covariance: model / n,
        empirical_covariance: scatter / n,
        ranges: readings.iter().map(|r| r.range).collect(),
        refractive_index: mean(|r| r.refractive_index),
        air,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_compensation::AirData;

    fn reading(t_ms: i64, target: &str, x: f64) -> ProcessedReading {
        ProcessedReading {
            time_ns: t_ms * 1_000_000,
            target: target.into(),
            range: x,
            azimuth: 0.0,
            elevation: 0.0,
            refractive_index: 1.00027,
            air: AirData {
                temperature: 20.0,
                pressure: 101_325.0,
                humidity: 0.5,
            },
            point: Vector3::new(x, 0.0, 0.0),
            covariance: Matrix3::identity() * 4e-12,
        }
    }

    #[test]
    fn dwells_split_on_target_change_motion_and_gaps() {
        let mut g = DwellGrouper::new(500_000_000);
        assert!(g.push(reading(0, "p0", 1.0)).is_none());
        assert!(g.push(reading(100, "p0", 1.000002)).is_none());
        assert!(g.push(reading(200, "p0", 1.000004)).is_none());
        let d = g
            .push(reading(300, "", 1.2))
            .expect("moving closes the dwell");
        assert_eq!(
            (d.target.as_str(), d.n, d.first_ns, d.last_ns),
            ("p0", 3, 0, 200_000_000)
        );
        assert!((d.point.x - 1.000002).abs() < 1e-12);
        // standard error by the model: σ²/n
        assert!((d.covariance[(0, 0)] - 4e-12 / 3.0).abs() < 1e-24);
        // by the scatter: sample variance (4e-12) / 3
        assert!((d.empirical_covariance[(0, 0)] - 4e-12 / 3.0).abs() < 1e-20);
        assert!(g.push(reading(400, "p1", 2.0)).is_none());
        let d = g
            .push(reading(1400, "p1", 2.0))
            .expect("a long gap starts a new visit");
        assert_eq!(d.n, 1);
        assert_eq!(g.close_if_stale(1_500_000_000), None);
        assert_eq!(g.close_if_stale(2_000_000_000).map(|d| d.n), Some(1));
        assert_eq!(g.flush(), None);
    }

    #[test]
    fn flagged_dwell_covariance_is_inflated_by_the_scatter() {
        let d = average(&[reading(0, "p", 1.0), reading(1, "p", 1.0)]).unwrap();
        let v = TurbulenceVerdict {
            statistic: 50.0,
            threshold: 10.0,
            dof: 1,
            scatter_ratio: 3.0,
            flagged: true,
        };
        assert_eq!(d.covariance_given(Some(&v)), d.covariance * 9.0);
        assert_eq!(
            d.covariance_given(Some(&TurbulenceVerdict {
                flagged: false,
                ..v
            })),
            d.covariance
        );
        assert_eq!(d.covariance_given(None), d.covariance);
    }
}
