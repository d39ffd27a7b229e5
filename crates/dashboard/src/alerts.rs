//! Alerting: thresholds on the predicted volumetric error magnitude and on the drift rate of a
//! stream of measured points, as `diagnostic_msgs/DiagnosticStatus` (OK/WARN/ERROR with values).
//!
//! Thresholds are given in the units people read (µm, µm/h) and held in SI (m, m/s). A level is
//! raised only when the value exceeds the threshold by more than `coverage_k`·σ of its own
//! uncertainty, so a noisy fit over a short window does not page anyone; the drift is judged
//! only once the window spans `min_drift_span` seconds.

use metrocell_msgs::diagnostic_msgs::msg::{DiagnosticStatus, KeyValue};
use serde::Serialize;

use crate::volumetric::VolumetricSummary;

const UM: f64 = 1e-6;
const UM_PER_H: f64 = 1e-6 / 3600.0;

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AlertThresholds {
    /// |predicted error| [m]
    pub error_warn: f64,
    pub error_error: f64,
    /// |drift rate| of the worst axis [m/s]
    pub drift_warn: f64,
    pub drift_error: f64,
    /// A level is raised when |value| − k·σ exceeds its threshold.
    pub coverage_k: f64,
    /// Shortest window [s] over which a drift rate is judged.
    pub min_drift_span: f64,
}

impl AlertThresholds {
    /// From µm and µm/h (the node's parameters `error_warn_um`, `drift_warn_um_per_h`, ...).
    pub fn from_um(
        error_warn_um: f64,
        error_error_um: f64,
        drift_warn_um_per_h: f64,
        drift_error_um_per_h: f64,
        coverage_k: f64,
        min_drift_span: f64,
    ) -> Result<Self, String> {
        for (name, v) in [
            ("error_warn_um", error_warn_um),
            ("error_error_um", error_error_um),
            ("drift_warn_um_per_h", drift_warn_um_per_h),
            ("drift_error_um_per_h", drift_error_um_per_h),
            ("coverage_k", coverage_k),
            ("min_drift_span", min_drift_span),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!(
                    "alert threshold {name} = {v} must be finite and ≥ 0"
                ));
            }
        }
        if error_error_um < error_warn_um || drift_error_um_per_h < drift_warn_um_per_h {
            return Err(format!(
                "alert thresholds: the ERROR level must not be below the WARN level (error {error_warn_um}/{error_error_um} µm, drift {drift_warn_um_per_h}/{drift_error_um_per_h} µm/h)"
            ));
        }
        Ok(AlertThresholds {
            error_warn: error_warn_um * UM,
            error_error: error_error_um * UM,
            drift_warn: drift_warn_um_per_h * UM_PER_H,
            drift_error: drift_error_um_per_h * UM_PER_H,
            coverage_k,
            min_drift_span,
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Level {
    #[serde(rename = "OK")]
    Ok,
    #[serde(rename = "WARN")]
    Warn,
    #[serde(rename = "ERROR")]
    Error,
}

impl Level {
    pub fn as_byte(self) -> u8 {
        match self {
            Level::Ok => DiagnosticStatus::OK,
            Level::Warn => DiagnosticStatus::WARN,
            Level::Error => DiagnosticStatus::ERROR,
        }
    }
}

/// One judged quantity.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Alert {
    /// e.g. `volumetric_error /measured_points`.
    pub name: String,
    pub level: Level,
    /// In words, with the numbers in µm or µm/h.
    pub message: String,
    /// SI value, its σ and the thresholds (m or m/s).
    pub value: f64,
    pub sigma: f64,
    pub warn: f64,
    pub error: f64,
    /// "m" or "m/s".
    pub unit: &'static str,
    /// Stamp of the data judged [s since the epoch].
    pub stamp: f64,
}

fn level_of(value: f64, sigma: f64, warn: f64, error: f64, k: f64) -> Level {
    let lower = value.abs() - k * sigma;
    if lower > error {
        Level::Error
    } else if lower > warn {
        Level::Warn
    } else {
        Level::Ok
    }
}

/// The alerts of one stream (`topic`): its predicted error magnitude and, once the window is
/// long enough, its worst axis drift.
pub fn evaluate(topic: &str, s: &VolumetricSummary, th: &AlertThresholds) -> Vec<Alert> {
    let level = level_of(
        s.magnitude,
        s.magnitude_sigma,
        th.error_warn,
        th.error_error,
        th.coverage_k,
    );
    let mut out = vec![Alert {
        name: format!("volumetric_error {topic}"),
        level,
        message: format!(
            "predicted volumetric error {:.1} ± {:.1} µm (warn {:.1}, error {:.1} µm)",
            s.magnitude / UM,
            s.magnitude_sigma / UM,
            th.error_warn / UM,
            th.error_error / UM
        ),
        value: s.magnitude,
        sigma: s.magnitude_sigma,
        warn: th.error_warn,
        error: th.error_error,
        unit: "m",
        stamp: s.stamp,
    }];
    if let Some((rate, sigma, axis)) = s.max_drift.filter(|_| s.window_span >= th.min_drift_span) {
        let level = level_of(rate, sigma, th.drift_warn, th.drift_error, th.coverage_k);
        out.push(Alert {
            name: format!("drift_rate {topic}"),
            level,
            message: format!(
                "{axis} drifts {:+.1} ± {:.1} µm/h over {:.0} s (warn {:.1}, error {:.1} µm/h)",
                rate / UM_PER_H,
                sigma / UM_PER_H,
                s.window_span,
                th.drift_warn / UM_PER_H,
                th.drift_error / UM_PER_H
            ),
            value: rate,
            sigma,
            warn: th.drift_warn,
            error: th.drift_error,
            unit: "m/s",
            stamp: s.stamp,
        });
    }
    out
}

/// The statuses published on `/diagnostics`, named `<node>: <alert name>`; values in SI.
pub fn to_statuses(node_fqn: &str, alerts: &[Alert]) -> Vec<DiagnosticStatus> {
    alerts
        .iter()
        .map(|a| {
            let kv = |key: &str, v: f64| KeyValue {
                key: format!("{key} [{}]", a.unit),
                value: format!("{v:e}"),
            };
            DiagnosticStatus {
                level: a.level.as_byte(),
                name: format!("{node_fqn}: {}", a.name),
                message: a.message.clone(),
                hardware_id: String::new(),
                values: vec![
                    kv("value", a.value),
                    kv("sigma", a.sigma),
                    kv("warn", a.warn),
                    kv("error", a.error),
                ],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volumetric::tests::point;
    use crate::volumetric::VolumetricError;

    fn thresholds() -> AlertThresholds {
        AlertThresholds::from_um(20.0, 50.0, 10.0, 30.0, 2.0, 600.0).unwrap()
    }

    fn ramp(rate_um_per_h: f64, minutes: usize) -> VolumetricSummary {
        let mut v = VolumetricError::new(7200.0, 10_000);
        for k in 0..=minutes {
            let h = k as f64 / 60.0;
            v.push(&point(
                1.0e9 + 60.0 * k as f64,
                [0.0; 3],
                [rate_um_per_h * 1e-6 * h, 0.0, 0.0],
            ))
            .unwrap();
        }
        v.summary(10).unwrap()
    }

    #[test]
    fn units_convert_to_si() {
        let t = thresholds();
        assert!(
            (t.error_warn - 20e-6).abs() < 1e-18 && (t.drift_error - 30e-6 / 3600.0).abs() < 1e-20
        );
        assert!(AlertThresholds::from_um(20.0, 10.0, 1.0, 2.0, 2.0, 0.0)
            .unwrap_err()
            .contains("must not be below"));
        assert!(AlertThresholds::from_um(f64::NAN, 10.0, 1.0, 2.0, 2.0, 0.0)
            .unwrap_err()
            .contains("error_warn_um"));
    }

    #[test]
    fn a_ramp_crosses_warn_then_error_as_it_grows() {
        let th = thresholds();
        // 12 µm/h for an hour: drift above 10 µm/h → WARN; error 12 µm < 20 → OK
        let a = evaluate("/measured_points", &ramp(12.0, 60), &th);
        assert_eq!((a[0].level, a[1].level), (Level::Ok, Level::Warn), "{a:?}");
        assert!(
            a[1].message
                .starts_with("x drifts +12.0 ± 0.0 µm/h over 3600 s"),
            "{}",
            a[1].message
        );
        // 40 µm/h for an hour: drift → ERROR, error 40 µm → WARN
        let a = evaluate("/measured_points", &ramp(40.0, 60), &th);
        assert_eq!((a[0].level, a[1].level), (Level::Warn, Level::Error));
        // 60 µm/h: error 60 µm → ERROR
        assert_eq!(evaluate("/p", &ramp(60.0, 60), &th)[0].level, Level::Error);
        // the same steep ramp over 5 minutes is too short a window to judge drift
        assert_eq!(evaluate("/p", &ramp(600.0, 5), &th).len(), 1);
    }

    #[test]
    fn an_uncertain_value_just_over_the_threshold_stays_ok() {
        let mut s = ramp(0.0, 60);
        (s.magnitude, s.magnitude_sigma) = (25e-6, 4e-6);
        assert_eq!(evaluate("/p", &s, &thresholds())[0].level, Level::Ok); // 25 − 2·4 = 17 < 20
        s.magnitude_sigma = 2e-6; // 25 − 4 = 21 > 20
        assert_eq!(evaluate("/p", &s, &thresholds())[0].level, Level::Warn);
    }

    #[test]
    fn statuses_carry_level_name_and_si_values() {
        let a = evaluate("/measured_points", &ramp(40.0, 60), &thresholds());
        let s = to_statuses("/dashboard", &a);
        assert_eq!(
            (s[1].name.as_str(), s[1].level),
            ("/dashboard: drift_rate /measured_points", 2)
        );
        assert_eq!(s[0].values[0].key, "value [m]");
        let v: f64 = s[0].values[0].value.parse().unwrap();
        assert!((v - 40e-6).abs() < 1e-12);
        assert_eq!(s[1].values[2].key, "warn [m/s]");
    }
}
