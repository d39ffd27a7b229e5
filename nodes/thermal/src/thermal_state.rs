//! The node's logic with time passed in (`now_ns`): live it is the node clock, on a bag it is
//! the bag's log time, so a replay makes the same decisions (staleness, model period) as the
//! live run that was recorded. The lags and the online fit run on the messages' header stamps
//! (the time the sensor read, which a recording keeps), not on the receive time.

use std::collections::BTreeMap;

use metrocell_compensation::{
    GrowthFitResult, Reading, ScaleFitResult, ThermalCompensator, ThermalError,
};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use nalgebra::{Matrix2, Matrix3, Vector3};

use crate::parameters::{AlphaFitConfig, FitConfig};

/// What the node counts (diagnostics, and the replay's summary).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Counters {
    pub points_compensated: u64,
    /// by reason: no_reading, stale_sensor, not_finite, model_error
    pub points_not_compensated: BTreeMap<&'static str, u64>,
    pub rejected_readings: u64,
}

impl Counters {
    pub fn not_compensated_total(&self) -> u64 {
        self.points_not_compensated.values().sum()
    }
    pub fn summary(&self) -> String {
        let reasons = self
            .points_not_compensated
            .iter()
            .map(|(r, n)| format!("{r}: {n}"))
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "{} points compensated, {} not ({reasons}), {} readings rejected",
            self.points_compensated,
            self.not_compensated_total(),
            self.rejected_readings
        )
    }
}

pub struct ThermalState {
    pub compensator: ThermalCompensator,
    pub fit: Option<FitConfig>,
    /// Latest accepted fit, and whether its values are in use.
    pub fit_result: Option<(GrowthFitResult, bool)>,
    /// Stamp (s) of the measurement that triggered the last refit.
    last_fit_time: Option<f64>,
    pub alpha_fit: Option<AlphaFitConfig>,
    /// Latest fit of α, and whether it is in use.
    pub alpha_fit_result: Option<(ScaleFitResult, bool)>,
    /// Stamp (s) of the last α-fit event reported.
    last_alpha_report: Option<f64>,
    pub counters: Counters,
    drift_point: Vector3<f64>,
    calibration_variance: f64,
    limits: (f64, f64),
    period_ns: i64,
    stale_after_ns: i64,
    /// sensor → (temperature °C, variance K², receive time ns, stamp s)
    latest: BTreeMap<String, (f64, f64, i64, f64)>,
    next_model_ns: Option<i64>,
}

/// Outcome of a measurement of an α reference point (for the node to log).
pub enum AlphaFitEvent {
    /// fitted, configured α kept (not enough measurements yet)
    Fitted(ScaleFitResult),
    /// the fitted α is in use
    Used(ScaleFitResult),
    NotYet(String),
}

/// Outcome of a reference-point measurement for the fit (for the node to log).
pub enum FitEvent {
    Fitted(GrowthFitResult),
    Used(GrowthFitResult),
    NotYet(String),
}

pub struct Settings {
    pub period_s: f64,
    pub stale_after_s: f64,
    pub calibration_uncertainty: f64,
    pub limits: (f64, f64),
    pub drift_point: Vector3<f64>,
}

fn stamp_seconds(t: &metrocell_msgs::builtin_interfaces::msg::Time) -> f64 {
    t.sec as f64 + t.nanosec as f64 * 1e-9
}

impl ThermalState {
    pub fn new(compensator: ThermalCompensator, fit: Option<FitConfig>, s: Settings) -> Self {
        Self {
            compensator,
            fit,
            fit_result: None,
            last_fit_time: None,
            alpha_fit: None,
            alpha_fit_result: None,
            last_alpha_report: None,
            counters: Counters::default(),
            drift_point: s.drift_point,
            calibration_variance: s.calibration_uncertainty.powi(2),
            limits: s.limits,
            period_ns: (s.period_s * 1e9).round() as i64,
            stale_after_ns: (s.stale_after_s * 1e9).round() as i64,
            latest: BTreeMap::new(),
            next_model_ns: None,
        }
    }

    /// With the online fit of α.
    pub fn with_alpha_fit(mut self, alpha_fit: Option<AlphaFitConfig>) -> Self {
        self.alpha_fit = alpha_fit;
        self
    }

    /// If `p` is one of the α fit's reference points, add its error along the fitted axis
    /// (measured − nominal, less the drift of every other term) against the lever
    /// q·(T(q) − T_ref) and refit; once `min_observations` measurements are in, the fitted α and
    /// its uncertainty replace the configured ones (and keep following the fit). Events are
    /// reported at most every `interval` s (message stamps), and always when the fitted α is
    /// first used.
    pub fn alpha_reference_measurement(&mut self, p: &MeasuredPoint) -> Option<AlphaFitEvent> {
        let a = self.alpha_fit.as_ref()?;
        let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
        let j = a.point_index(&nominal)?;
        let k = a.axis;
        let reading = |n: &str| self.reading(n);
        let lever = match self.compensator.scale.axis_lever(k, &nominal, &reading) {
            Ok(l) => l,
            Err(e) => {
                return Some(AlphaFitEvent::NotYet(format!(
                    "alpha reference point not used: {e}"
                )))
            }
        };
        let all = match self.compensator.drift(&nominal, &reading) {
            Ok((d, _)) => d,
            Err(e) => {
                return Some(AlphaFitEvent::NotYet(format!(
                    "alpha reference point not used: {e}"
                )))
            }
        };
        // the error along the axis less every other term's drift (this axis's scale term is α·lever)
        let error = [p.measured.x, p.measured.y, p.measured.z][k]
            - nominal[k]
            - (all[k] - self.compensator.scale.alpha * lever);
        let variance = Matrix3::from_row_slice(&p.covariance)[(k, k)];
        let time = stamp_seconds(&p.header.stamp);
        let a = self.alpha_fit.as_mut()?;
        if let Err(e) = a.fit.add_observation(j, lever, error, variance) {
            return Some(AlphaFitEvent::NotYet(e.to_string()));
        }
        let r = match a.fit.fit() {
            Ok(r) => r,
            Err(e) => return Some(AlphaFitEvent::NotYet(e.to_string())),
        };
        let was_used = self
            .alpha_fit_result
            .as_ref()
            .is_some_and(|(_, used)| *used);
        let mut used = false;
        let mut refused = None;
        if r.observations >= a.min_observations {
            match self
                .compensator
                .scale
                .use_alpha(r.alpha, r.alpha_uncertainty)
            {
                Ok(()) => used = true,
                Err(e) => {
                    refused = Some(format!(
                        "fitted alpha {:e} ± {:e} 1/K not used: {e}",
                        r.alpha, r.alpha_uncertainty
                    ))
                }
            }
        }
        self.alpha_fit_result = Some((r.clone(), used));
        let due = self
            .last_alpha_report
            .is_none_or(|t| time - t >= a.interval)
            || (used && !was_used);
        if !due {
            return None;
        }
        self.last_alpha_report = Some(time);
        Some(match (refused, used) {
            (Some(why), _) => AlphaFitEvent::NotYet(why),
            (None, true) => AlphaFitEvent::Used(r),
            (None, false) => AlphaFitEvent::Fitted(r),
        })
    }

    /// Store a reading; `Err` names why it was rejected (and counts it).
    pub fn temperature(
        &mut self,
        sensor: &str,
        t: &Temperature,
        now_ns: i64,
    ) -> Result<(), String> {
        let (lo, hi) = self.limits;
        let problem = if !(t.temperature.is_finite() && t.variance.is_finite() && t.variance >= 0.0)
        {
            Some("not a finite value with a variance ≥ 0".to_string())
        } else if !(t.temperature >= lo && t.temperature <= hi) {
            Some(format!("outside temperature_limits [{lo}, {hi}] °C"))
        } else if self.is_lagged(sensor)
            && self
                .latest
                .get(sensor)
                .is_some_and(|r| stamp_seconds(&t.header.stamp) <= r.3)
        {
            Some(
                "its stamp is not later than the previous reading's (a lag cannot go back in time)"
                    .to_string(),
            )
        } else {
            None
        };
        if let Some(why) = problem {
            self.counters.rejected_readings += 1;
            return Err(format!(
                "temperature/{sensor}: rejected reading {} °C (variance {}): {why}",
                t.temperature, t.variance
            ));
        }
        let time = stamp_seconds(&t.header.stamp);
        self.compensator
            .observe(sensor, time, t.temperature, t.variance);
        if let Some(f) = &mut self.fit {
            if self.compensator.growth[f.growth_index].spec.sensor == sensor {
                f.fit.add_reading(time, t.temperature, t.variance);
            }
        }
        self.latest.insert(
            sensor.to_string(),
            (t.temperature, t.variance, now_ns, time),
        );
        Ok(())
    }

    fn is_lagged(&self, sensor: &str) -> bool {
        self.compensator
            .growth
            .iter()
            .any(|g| g.spec.sensor == sensor && g.spec.time_constant.is_some())
    }

    /// The latest reading with the calibration variance added, if there is one.
    fn reading(&self, name: &str) -> Option<Reading> {
        self.latest
            .get(name)
            .map(|r| (r.0, r.1 + self.calibration_variance))
    }

    /// Sensors with no reading yet or none within `stale_after` at `now_ns`.
    pub fn stale_sensors(&self, now_ns: i64) -> Vec<String> {
        self.compensator
            .sensor_names()
            .into_iter()
            .filter(|n| {
                self.latest
                    .get(n)
                    .is_none_or(|r| now_ns - r.2 > self.stale_after_ns)
            })
            .collect()
    }

    fn check_fresh(&self, now_ns: i64) -> Result<(), ThermalError> {
        for name in self.compensator.sensor_names() {
            if let Some(r) = self.latest.get(&name) {
                if now_ns - r.2 > self.stale_after_ns {
                    return Err(ThermalError::StaleReading {
                        sensor: name,
                        age_s: (now_ns - r.2) as f64 * 1e-9,
                        limit_s: self.stale_after_ns as f64 * 1e-9,
                    });
                }
            }
        }
        Ok(())
    }

    /// The point with the thermal drift removed and its covariance enlarged; counted either way.
    pub fn compensate(
        &mut self,
        p: &MeasuredPoint,
        now_ns: i64,
    ) -> Result<MeasuredPoint, ThermalError> {
        let out = self.compensate_point(p, now_ns);
        match &out {
            Ok(_) => self.counters.points_compensated += 1,
            Err(e) => {
                *self
                    .counters
                    .points_not_compensated
                    .entry(e.reason())
                    .or_default() += 1
            }
        }
        out
    }

    fn compensate_point(
        &self,
        p: &MeasuredPoint,
        now_ns: i64,
    ) -> Result<MeasuredPoint, ThermalError> {
        self.check_fresh(now_ns)?;
        let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
        let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
        let cov = Matrix3::from_row_slice(&p.covariance);
        let (c, c_cov) = self
            .compensator
            .compensate(&nominal, &measured, &cov, &|n: &str| self.reading(n))?;
        let mut out = p.clone();
        (out.measured.x, out.measured.y, out.measured.z) = (c.x, c.y, c.z);
        out.covariance.copy_from_slice(c_cov.transpose().as_slice());
        Ok(out)
    }

    /// If `p` is the fit's reference point, add its error (measured − nominal, less the drift
    /// of every other term) and refit; once enough measurements fit with τ inside its range,
    /// the fitted g and τ are used.
    pub fn reference_measurement(&mut self, p: &MeasuredPoint) -> Option<FitEvent> {
        let f = self.fit.as_ref()?;
        let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
        // `!(a <= b)` also rejects a NaN nominal
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !((nominal - f.point).norm() <= f.tolerance) {
            return None;
        }
        let others = self
            .compensator
            .drift(&nominal, &|n: &str| self.reading(n))
            .and_then(|(all, _)| {
                Ok(all
                    - self.compensator.growth[f.growth_index]
                        .drift(&nominal)?
                        .displacement)
            });
        let others = match others {
            Ok(d) => d,
            Err(e) => return Some(FitEvent::NotYet(format!("reference point not used: {e}"))),
        };
        let f = self.fit.as_mut()?;
        let error = Vector3::new(p.measured.x, p.measured.y, p.measured.z) - nominal - others;
        let time = stamp_seconds(&p.header.stamp);
        if let Err(e) = f
            .fit
            .add_observation(time, &error, &Matrix3::from_row_slice(&p.covariance))
        {
            return Some(FitEvent::NotYet(e.to_string()));
        }
        if self.last_fit_time.is_some_and(|t| time - t < f.interval) {
            return None;
        }
        self.last_fit_time = Some(time);
        let r = match f.fit.fit() {
            Ok(r) => r,
            Err(e) => return Some(FitEvent::NotYet(e.to_string())),
        };
        let usable = r.observations >= f.min_observations && !r.at_bound;
        if usable {
            let cov = Matrix2::new(
                r.covariance[(1, 1)],
                r.covariance[(1, 2)],
                r.covariance[(2, 1)],
                r.covariance[(2, 2)],
            );
            let lag = f.fit.lag(r.time_constant);
            if let Err(e) = self.compensator.growth[f.growth_index].use_fitted(
                r.coefficient,
                r.time_constant,
                cov,
                lag,
            ) {
                return Some(FitEvent::NotYet(e.to_string()));
            }
        }
        self.fit_result = Some((r.clone(), usable));
        Some(if usable {
            FitEvent::Used(r)
        } else {
            FitEvent::Fitted(r)
        })
    }

    /// The error model and the predicted drift when due at `now_ns` (first call, then every period).
    pub fn model_if_due(
        &mut self,
        now_ns: i64,
    ) -> Option<(
        Result<ErrorModel, ThermalError>,
        Result<MeasuredPoint, ThermalError>,
    )> {
        let due = self.next_model_ns.is_none_or(|t| now_ns >= t);
        if !due {
            return None;
        }
        // next = previous deadline + period; after a gap longer than a period (e.g. in a bag)
        // restart from now instead of publishing a burst.
        let next = self.next_model_ns.unwrap_or(now_ns) + self.period_ns;
        self.next_model_ns = Some(if next <= now_ns {
            now_ns + self.period_ns
        } else {
            next
        });
        let reading = |n: &str| self.reading(n);
        let model = self.check_fresh(now_ns).and_then(|_| {
            crate::model_message::error_model(
                &self.compensator,
                self.fit_result.as_ref(),
                &reading,
                now_ns,
            )
        });
        let drift = self.check_fresh(now_ns).and_then(|_| {
            crate::model_message::predicted_drift(
                &self.compensator,
                &self.drift_point,
                &reading,
                now_ns,
            )
        });
        Some((model, drift))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_msgs::builtin_interfaces::msg::Time;
    use metrocell_msgs::geometry_msgs::msg::Point;
    use metrocell_msgs::std_msgs::msg::Header;

    const S: i64 = 1_000_000_000;

    /// From the node's own parameters: x scale on x_left/x_right (u(α) by the ISO/TR 230-9 rule),
    /// column growth 4 µm/K down with a 600 s lag; stale after 10 s; limits [-20, 80] °C.
    fn state() -> ThermalState {
        state_with(&[])
    }

    fn state_with(extra: &[&'static str]) -> ThermalState {
        let mut args = vec![
            "metrocell-thermal",
            "--ros-args",
            "-p",
            "sensors:=[x_left, x_right]",
            "-p",
            "sensor_axes:=[x, x]",
            "-p",
            "sensor_positions:=[0.0, 0.8]",
            "-p",
            "alpha_uncertainty:=5.77e-7",
            "-p",
            "sensor_calibration_uncertainty:=0.05",
            "-p",
            "growth_sensors:=[column]",
            "-p",
            "growth_directions:=[0.0, 0.0, -1.0]",
            "-p",
            "growth_coefficients:=[4e-6]",
            "-p",
            "growth_time_constants:=[600.0]",
            "-p",
            "growth_time_constant_uncertainties:=[60.0]",
            "-p",
            "growth_coefficient_uncertainties:=[4e-7]",
            "-p",
            "drift_point:=[0.4, 0.0, 0.0]",
        ];
        for p in extra {
            args.extend(["-p", p]);
        }
        let cl = metrocell_node::parse_command_line(args).unwrap();
        let p = metrocell_node::Parameters::resolve(
            &crate::parameters::declarations(),
            &cl.ros,
            "/thermal",
            "thermal",
        )
        .unwrap();
        let log = std::cell::RefCell::new(Vec::new());
        let st = crate::start(&p, &|line| log.borrow_mut().push(line)).unwrap();
        let log = log.into_inner();
        assert!(
            log[0].contains("strain computed from the configured alpha=1.15e-5"),
            "{log:?}"
        );
        assert!(
            log[1].starts_with(
                "thermal_growth[column]: configured g=4e-6 m/K ± 4e-7, lag τ=600 s ± 60 s"
            ),
            "{log:?}"
        );
        st
    }

    fn temp(value: f64, at_ns: i64) -> Temperature {
        Temperature {
            header: Header {
                stamp: Time::from_nanos(at_ns),
                frame_id: String::new(),
            },
            temperature: value,
            variance: 0.0004,
        }
    }

    fn point(x: f64) -> MeasuredPoint {
        MeasuredPoint {
            header: Header::default(),
            point_id: "p".into(),
            source: "tracker".into(),
            nominal: Point { x, y: 0.0, z: 0.2 },
            measured: Point { x, y: 0.0, z: 0.2 },
            covariance: [1e-12, 0.0, 0.0, 0.0, 1e-12, 0.0, 0.0, 0.0, 1e-12],
        }
    }

    fn feed_all(st: &mut ThermalState, at_ns: i64) {
        for (n, v) in [("x_left", 21.0), ("x_right", 22.0), ("column", 23.0)] {
            st.temperature(n, &temp(v, at_ns), at_ns).unwrap();
        }
    }

    #[test]
    fn compensates_every_term_and_counts_it() {
        let mut st = state();
        feed_all(&mut st, 0);
        let out = st.compensate(&point(0.8), S).unwrap();
        // x: α·0.8 m·(22 − 20) K removed; z: the column at 23 °C (one reading, so T_f = 23) grows 12 µm down
        assert!((out.measured.x - (0.8 - 11.5e-6 * 0.8 * 2.0)).abs() < 1e-15);
        assert!((out.measured.z - (0.2 + 12e-6)).abs() < 1e-15);
        assert!(
            out.covariance[0] > 1e-12 && out.covariance[8] > 1e-12,
            "covariance enlarged: {:?}",
            out.covariance
        );
        assert_eq!(st.counters.points_compensated, 1);
        let (model, drift) = st.model_if_due(S).unwrap();
        let model = model.unwrap();
        assert_eq!(
            model.parameter_names,
            [
                "thermal_scale[x].alpha",
                "thermal_scale[x].strain",
                "thermal_growth[column].coefficient",
                "thermal_growth[column].time_constant"
            ]
        );
        assert_eq!(model.units, ["1/K", "m/m", "m/K", "s"]);
        assert_eq!(model.covariance.len(), 16);
        assert!(
            (model.covariance[15] - 3600.0).abs() < 1e-9,
            "u(τ)² on the diagonal"
        );
        let drift = drift.unwrap();
        assert!(
            (drift.measured.x - drift.nominal.x - 11.5e-6 * 0.4 * 1.5).abs() < 1e-15,
            "drift point at x = 0.4 m, T = 21.5 °C"
        );
        assert!((drift.measured.z - drift.nominal.z + 12e-6).abs() < 1e-15);
    }

    #[test]
    fn missing_sensor_is_counted_as_no_reading() {
        let mut st = state();
        st.temperature("x_left", &temp(21.0, 0), 0).unwrap();
        st.temperature("column", &temp(21.0, 0), 0).unwrap();
        let e = st.compensate(&point(0.5), S).unwrap_err();
        assert_eq!(e, ThermalError::NoReading("x_right".into(), "x"));
        assert_eq!(
            st.counters.points_not_compensated.get("no_reading"),
            Some(&1)
        );
        assert_eq!(st.counters.points_compensated, 0);
        assert_eq!(st.stale_sensors(S), ["x_right"]);
    }

    #[test]
    fn stale_sensor_stops_compensation_and_is_reported() {
        let mut st = state();
        feed_all(&mut st, 0);
        // 5 s later x_left and column report again, x_right does not
        st.temperature("x_left", &temp(21.0, 5 * S), 5 * S).unwrap();
        st.temperature("column", &temp(23.0, 5 * S), 5 * S).unwrap();
        assert!(
            st.compensate(&point(0.5), 10 * S).is_ok(),
            "10 s old is still fresh"
        );
        let e = st.compensate(&point(0.5), 11 * S).unwrap_err();
        assert!(
            matches!(&e, ThermalError::StaleReading { sensor, .. } if sensor == "x_right"),
            "{e}"
        );
        assert!(
            e.to_string().contains("x_right") && e.to_string().contains("11.0 s old"),
            "{e}"
        );
        assert_eq!(
            st.counters.points_not_compensated.get("stale_sensor"),
            Some(&1)
        );
        assert_eq!(st.stale_sensors(11 * S), ["x_right"]);
        let (model, drift) = st.model_if_due(11 * S).unwrap();
        assert!(
            model.is_err() && drift.is_err(),
            "no model from a stale sensor"
        );
        assert!(
            st.counters
                .summary()
                .contains("1 points compensated, 1 not (stale_sensor: 1)"),
            "{}",
            st.counters.summary()
        );
    }

    #[test]
    fn rejected_readings_are_counted_and_not_used() {
        let mut st = state();
        feed_all(&mut st, 0);
        for (v, why) in [
            (f64::NAN, "not a finite value"),
            (95.0, "outside temperature_limits"),
            (-40.0, "outside temperature_limits"),
        ] {
            let e = st.temperature("x_right", &temp(v, S), S).unwrap_err();
            assert!(e.contains("temperature/x_right") && e.contains(why), "{e}");
        }
        let mut bad_variance = temp(22.0, S);
        bad_variance.variance = -1.0;
        assert!(st.temperature("x_right", &bad_variance, S).is_err());
        // a lagged sensor's reading stamped before the previous one
        let e = st.temperature("column", &temp(23.0, 0), S).unwrap_err();
        assert!(e.contains("not later"), "{e}");
        assert_eq!(st.counters.rejected_readings, 5);
        // the last good reading (22 °C) is still the one used
        let out = st.compensate(&point(0.8), 2 * S).unwrap();
        assert!((out.measured.x - (0.8 - 11.5e-6 * 0.8 * 2.0)).abs() < 1e-15);
    }

    #[test]
    fn non_finite_point_is_counted() {
        let mut st = state();
        feed_all(&mut st, 0);
        let mut p = point(0.5);
        p.measured.y = f64::NAN;
        assert_eq!(st.compensate(&p, S).unwrap_err().reason(), "not_finite");
        let mut p = point(0.5);
        p.nominal.z = f64::INFINITY;
        assert_eq!(st.compensate(&p, S).unwrap_err().reason(), "not_finite");
        assert_eq!(
            st.counters.points_not_compensated.get("not_finite"),
            Some(&2)
        );
    }

    #[test]
    fn online_fit_replaces_the_configured_growth_once_it_fits() {
        // Truth g = 5 µm/K, τ = 1500 s (configured: 4 µm/K, 600 s). The column warms 3 K in 1.5-h
        // blocks; the reference point (0.1, 0.1, 0.1) is measured every 5 min with 1 µm noise.
        let mut st = state_with(&[
            "fit_reference_point:=[0.1, 0.1, 0.1]",
            "fit_min_observations:=20",
            "stale_after:=100.0",
            "fit_interval:=600.0",
        ]);
        assert!(st.fit.is_some());
        let (g_true, tau_true) = (5e-6, 1500.0);
        let mut truth = metrocell_compensation::FirstOrderLag::new(tau_true);
        let (mut column, mut used_at) = (20.0, None);
        for k in 0..(6 * 360) {
            let t_ns = k as i64 * 10 * S;
            let heating = if (k as f64 / 360.0) % 2.5 < 1.5 {
                3.0
            } else {
                0.0
            };
            column += (20.0 + heating - column) * (1.0 - (-10.0f64 / 3600.0).exp());
            truth.advance(t_ns as f64 * 1e-9, column, 0.0);
            for (n, v) in [("x_left", 20.0), ("x_right", 20.0), ("column", column)] {
                st.temperature(n, &temp(v, t_ns), t_ns).unwrap();
            }
            if k % 30 == 29 {
                let (_, tf, _, _) = truth.output().unwrap();
                // deterministic ±1 µm "noise" that does not correlate with the heating
                let noise = 1e-6 * ((k as f64) * 0.7).sin();
                let mut p = point(0.1);
                p.header.stamp = Time::from_nanos(t_ns);
                (p.nominal.y, p.nominal.z) = (0.1, 0.1);
                (p.measured.y, p.measured.z) = (0.1, 0.1 - g_true * (tf - 20.0) + noise);
                if let Some(FitEvent::Used(_)) = st.reference_measurement(&p) {
                    used_at.get_or_insert(k);
                }
            }
        }
        // refits every 600 s (every other measurement, from the first), so from the 21st on
        assert_eq!(
            used_at,
            Some(21 * 30 - 1),
            "used from the first refit with ≥ 20 measurements"
        );
        let (r, used) = st.fit_result.clone().unwrap();
        assert!(used && st.compensator.growth[0].is_fitted());
        let (ug, utau) = (r.covariance[(1, 1)].sqrt(), r.covariance[(2, 2)].sqrt());
        assert!(
            (r.coefficient - g_true).abs() < 3.0 * ug && ug < 0.5e-6,
            "g {} ± {ug}",
            r.coefficient
        );
        assert!(
            (r.time_constant - tau_true).abs() < 3.0 * utau && utau < 300.0,
            "τ {} ± {utau}",
            r.time_constant
        );
        // the error model now carries the fitted values, with the fit's covariance
        let (model, _) = st.model_if_due(6 * 3600 * S).unwrap();
        let model = model.unwrap();
        let i = model
            .parameter_names
            .iter()
            .position(|n| n == "thermal_growth[column].coefficient")
            .unwrap();
        assert_eq!(model.values[i], r.coefficient);
        assert_eq!(model.values[i + 1], r.time_constant);
        let n = model.values.len();
        assert_eq!(model.covariance[(i + 1) * n + i + 1], r.covariance[(2, 2)]);
        assert_eq!(model.degrees_of_freedom as usize, r.observations - 3);
        // and a point is now corrected with them: the reference point's Z error is gone to ~1 µm
        let (_, tf, _, _) = truth.output().unwrap();
        let mut p = point(0.1);
        (p.nominal.y, p.nominal.z, p.measured.y, p.measured.z) =
            (0.1, 0.1, 0.1, 0.1 - g_true * (tf - 20.0));
        let out = st.compensate(&p, 6 * 3600 * S).unwrap();
        assert!(
            (out.measured.z - 0.1).abs() < 1.5e-6,
            "left {:.2} µm",
            (out.measured.z - 0.1) * 1e6
        );
    }

    #[test]
    fn online_fit_of_alpha_replaces_the_configured_one() {
        // Truth α = 16e-6 1/K (configured 11.5e-6). The X scale warms from 19 to 23 °C (x_left
        // and x_right 0.5 K apart); reference points at x = 0.8 and 0.4 m with static X errors of
        // 6 and −4 µm are measured every 2 min, ±1 µm deterministic "noise".
        let mut st = state_with(&[
            "fit_alpha_points:=[0.8, 0.0, 0.2, 0.4, 0.0, 0.2]",
            "fit_alpha_min_observations:=30",
            "fit_interval:=0.0",
            "stale_after:=1000.0",
        ]);
        let alpha_true = 16e-6;
        let (mut used_at, mut events) = (None, 0);
        for k in 0..60 {
            let t_ns = k * 120 * S;
            let warm = 19.0 + 4.0 * k as f64 / 59.0;
            for (n, v) in [("x_left", warm), ("x_right", warm + 0.5), ("column", 20.0)] {
                st.temperature(n, &temp(v, t_ns), t_ns).unwrap();
            }
            for (q, c) in [(0.8, 6e-6), (0.4, -4e-6)] {
                let t_q = warm + 0.5 * q / 0.8;
                let mut p = point(q);
                p.header.stamp = Time::from_nanos(t_ns);
                p.measured.x =
                    q + c + alpha_true * q * (t_q - 20.0) + 1e-6 * ((k as f64) * 1.3 + q).sin();
                match st.alpha_reference_measurement(&p) {
                    Some(AlphaFitEvent::Used(_)) => {
                        used_at.get_or_insert(2 * k + (q < 0.5) as i64);
                        events += 1;
                    }
                    Some(_) => events += 1,
                    None => {}
                }
            }
        }
        assert_eq!(used_at, Some(29), "used from the 30th measurement on");
        assert!(
            events >= 100,
            "fit_interval 0: an event per measurement once it fits ({events})"
        );
        let (r, used) = st.alpha_fit_result.clone().unwrap();
        assert!(used);
        assert!(
            (r.alpha - alpha_true).abs() < 3.0 * r.alpha_uncertainty
                && r.alpha_uncertainty < 0.5e-6,
            "α {} ± {}",
            r.alpha,
            r.alpha_uncertainty
        );
        assert_eq!(
            (
                st.compensator.scale.alpha,
                st.compensator.scale.alpha_uncertainty
            ),
            (r.alpha, r.alpha_uncertainty)
        );
        // the error model carries the fitted α and u(α)²
        let (model, _) = st.model_if_due(59 * 120 * S).unwrap();
        let model = model.unwrap();
        let i = model
            .parameter_names
            .iter()
            .position(|n| n == "thermal_scale[x].alpha")
            .unwrap();
        assert_eq!(model.values[i], r.alpha);
        assert_eq!(
            model.covariance[i * model.values.len() + i],
            r.alpha_uncertainty.powi(2)
        );
        // a point at x = 0.6 m, 23.375 °C there, is corrected with the fitted α: its thermal error (9 µm with the configured α) is gone to < 0.5 µm
        let mut p = point(0.6);
        p.measured.x = 0.6 + alpha_true * 0.6 * (23.0 + 0.375 - 20.0);
        let out = st.compensate(&p, 59 * 120 * S).unwrap();
        assert!(
            (out.measured.x - 0.6).abs() < 0.5e-6,
            "left {:.3} µm",
            (out.measured.x - 0.6) * 1e6
        );
    }

    #[test]
    fn alpha_fit_needs_a_covered_axis() {
        let args = [
            "metrocell-thermal",
            "--ros-args",
            "-p",
            "sensors:=[x_left]",
            "-p",
            "sensor_axes:=[x]",
            "-p",
            "sensor_positions:=[0.0]",
            "-p",
            "fit_alpha_points:=[0.0, 0.5, 0.0]",
            "-p",
            "fit_alpha_axis:=y",
        ];
        let cl = metrocell_node::parse_command_line(args).unwrap();
        let p = metrocell_node::Parameters::resolve(
            &crate::parameters::declarations(),
            &cl.ros,
            "/thermal",
            "thermal",
        )
        .unwrap();
        let e = crate::start(&p, &|_| {}).err().unwrap().to_string();
        assert!(
            e.contains("fit_alpha_axis") && e.contains("no scale sensor"),
            "{e}"
        );
    }
}
