//! The temperature timeline: every sensor's samples of one recording (or one simulation), held
//! once and shared by every instant's [`crate::Signals`] through an `Arc` (cloning a `Signals`
//! copies a pointer, not an 8-hour history).
//!
//! Lagged temperatures (the first-order lag of `thermal_growth`, [`FirstOrderLag`]) are
//! evaluated incrementally: per (sensor, τ) the filtered series is kept, extended only as far as
//! it has been asked for, so evaluating one instant costs a binary search once the series is
//! filtered, not a pass over the history. The lag at time t is T_f at the last sample at or
//! before t — what a causal filter has seen at t. A changed τ (an estimator's next iterate)
//! filters the series once more; the last [`LAG_CACHES_PER_SENSOR`] values of τ are kept.
//!
//! The timeline grows while it is shared (the twin and a streaming signals builder append as
//! time advances; instants already handed out are unaffected, since each reads only samples at
//! or before its own time). Times are seconds on the recording's clock (the clock of
//! [`crate::Signals::time`]), strictly increasing per sensor; temperatures °C. With a capacity,
//! the oldest samples of a sensor are dropped beyond it and its lag restarts from the oldest
//! retained sample (as a history cut at that sample would).
//!
//! A streaming node that runs for days cannot keep every sample, yet a lag with a time constant
//! of hours needs the history before the instants it is asked about. With a full-rate span
//! ([`TemperatureTimeline::with_full_rate`]) the samples older than the span behind the newest
//! are coarsened to one per [`COARSE_BIN_S`] (each bin's mean value at its mean time), so memory
//! grows by 1/60 of the sample rate instead of all of it, and the lag at an instant inside the
//! span differs from the full history's by the coarsening's error seen through e^(−age/τ): tens
//! of µK for a 1 Hz thermocouple half an hour inside the span (unit test). Coarsening restarts
//! the lag caches (their indices moved); they are filtered again when next asked.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Mutex;

use crate::thermal::first_order_lag::FirstOrderLag;

/// Samples of one temperature sensor: (time s, temperature °C), strictly increasing in time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TemperatureHistory {
    pub samples: Vec<(f64, f64)>,
}

/// Values of τ whose filtered series are kept per sensor.
pub const LAG_CACHES_PER_SENSOR: usize = 8;

/// The coarsened history's sample spacing (s): a bin's samples become their mean.
pub const COARSE_BIN_S: f64 = 60.0;

/// Full-rate samples are coarsened once this much (s) of them has aged past the full-rate span,
/// so the work (a pass over the series) is done a few times per hour, not at every sample.
const COARSEN_BATCH_S: f64 = 600.0;

/// Why a lagged temperature could not be evaluated.
#[derive(Debug, Clone, PartialEq)]
pub enum LagUnavailable {
    /// The timeline has no sensor of that name.
    UnknownSensor,
    /// The sensor has no sample at or before the time asked for (`first`: its first sample, s).
    NoSampleYet { first: Option<f64> },
    /// τ is not > 0 and finite.
    BadTimeConstant,
}

#[derive(Debug)]
struct LagCache {
    tau_bits: u64,
    filter: FirstOrderLag,
    /// (T_f, ∂T_f/∂τ) after each sample, as far as asked for.
    values: Vec<(f64, f64)>,
}

#[derive(Debug, Default)]
struct Series {
    samples: VecDeque<(f64, f64)>,
    /// How many of the leading samples are coarsened already.
    coarse: usize,
    /// Most recently used last.
    lags: Vec<LagCache>,
}

impl Series {
    /// Coarsen the full-rate samples older than `boundary` (s) into bins of [`COARSE_BIN_S`].
    fn coarsen_before(&mut self, boundary: f64) {
        // the first sample stays as it is: every lag starts from it (its initial state), and a
        // bin's mean there would shift every lag by the start's difference times e^(−t/τ)
        self.coarse = self.coarse.max(1);
        let end = self.samples.partition_point(|(t, _)| *t < boundary);
        if end <= self.coarse {
            return;
        }
        let old: Vec<(f64, f64)> = self.samples.range(self.coarse..end).copied().collect();
        let mut binned: Vec<(f64, f64)> = Vec::new();
        let mut k = 0;
        while k < old.len() {
            let bin = (old[k].0 / COARSE_BIN_S).floor();
            let mut n = 0.0;
            let (mut st, mut sv) = (0.0, 0.0);
            while k < old.len() && (old[k].0 / COARSE_BIN_S).floor() == bin {
                st += old[k].0;
                sv += old[k].1;
                n += 1.0;
                k += 1;
            }
            binned.push((st / n, sv / n));
        }
        let tail: Vec<(f64, f64)> = self
            .samples
            .drain(self.coarse..)
            .skip(end - self.coarse)
            .collect();
        self.samples.extend(binned);
        self.coarse = self.samples.len();
        self.samples.extend(tail);
        self.lags.clear();
    }
}

#[derive(Debug, Default)]
struct Inner {
    capacity: Option<usize>,
    /// Seconds behind the newest sample kept at full rate (None: everything).
    full_rate: Option<f64>,
    sensors: BTreeMap<String, Series>,
}

/// Every sensor's samples, shared; see the module docs.
#[derive(Default)]
pub struct TemperatureTimeline {
    inner: Mutex<Inner>,
}

impl std::fmt::Debug for TemperatureTimeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let inner = self.lock();
        let mut m = f.debug_map();
        for (name, s) in &inner.sensors {
            m.entry(name, &format_args!("{} samples", s.samples.len()));
        }
        m.finish()
    }
}

impl TemperatureTimeline {
    pub fn new() -> Self {
        Self::default()
    }

    /// A timeline keeping at most `samples_per_sensor` samples of each sensor (the oldest go).
    pub fn with_capacity(samples_per_sensor: usize) -> Self {
        Self {
            inner: Mutex::new(Inner {
                capacity: Some(samples_per_sensor.max(1)),
                full_rate: None,
                sensors: BTreeMap::new(),
            }),
        }
    }

    /// A timeline keeping the last `seconds` of each sensor at full rate and the history before
    /// that coarsened to one sample per [`COARSE_BIN_S`] (see the module docs).
    pub fn with_full_rate(seconds: f64) -> Self {
        Self {
            inner: Mutex::new(Inner {
                capacity: None,
                full_rate: Some(seconds.max(COARSE_BIN_S)),
                sensors: BTreeMap::new(),
            }),
        }
    }

    /// A timeline holding the given histories (tests, tools); fails like [`Self::push`].
    pub fn from_histories<'a>(
        histories: impl IntoIterator<Item = (&'a str, &'a TemperatureHistory)>,
    ) -> Result<Self, String> {
        let t = Self::new();
        for (name, h) in histories {
            t.add_sensor(name);
            for &(time, value) in &h.samples {
                t.push(name, time, value)?;
            }
        }
        Ok(t)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic while the lock was held cannot leave the data inconsistent (every mutation
        // completes before it could panic), so a poisoned lock is used as is.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Declare a sensor (it then exists, without samples).
    pub fn add_sensor(&self, sensor: &str) {
        self.lock().sensors.entry(sensor.to_string()).or_default();
    }

    /// Append a sample. Fails (naming the sensor and the times) when the time does not come
    /// after the sensor's last sample or a value is not finite; the timeline is then unchanged.
    pub fn push(&self, sensor: &str, time: f64, temperature: f64) -> Result<(), String> {
        if !(time.is_finite() && temperature.is_finite()) {
            return Err(format!(
                "temperature sensor `{sensor}`: sample ({time} s, {temperature} °C) is not finite"
            ));
        }
        let mut inner = self.lock();
        let (capacity, full_rate) = (inner.capacity, inner.full_rate);
        let series = inner.sensors.entry(sensor.to_string()).or_default();
        if let Some(&(last, _)) = series.samples.back() {
            if !(time > last) {
                return Err(format!("temperature sensor `{sensor}`: sample at {time} s does not come after the previous one at {last} s (times must increase strictly)"));
            }
        }
        if capacity.is_some_and(|c| series.samples.len() >= c) {
            series.samples.pop_front();
            series.coarse = series.coarse.saturating_sub(1);
            series.lags.clear();
        }
        series.samples.push_back((time, temperature));
        if let Some(span) = full_rate {
            let oldest_full = series.samples.get(series.coarse).map_or(time, |s| s.0);
            if time - span - oldest_full >= COARSEN_BATCH_S {
                series.coarsen_before(time - span);
            }
        }
        Ok(())
    }

    pub fn contains(&self, sensor: &str) -> bool {
        self.lock().sensors.contains_key(sensor)
    }

    /// Names of the sensors, sorted.
    pub fn sensors(&self) -> Vec<String> {
        self.lock().sensors.keys().cloned().collect()
    }

    /// Number of samples of a sensor held now.
    pub fn sample_count(&self, sensor: &str) -> Option<usize> {
        self.lock().sensors.get(sensor).map(|s| s.samples.len())
    }

    /// (first, last) sample time of a sensor, s.
    pub fn time_span(&self, sensor: &str) -> Option<(f64, f64)> {
        let inner = self.lock();
        let s = inner.sensors.get(sensor)?;
        Some((s.samples.front()?.0, s.samples.back()?.0))
    }

    /// A copy of a sensor's samples at or before `until` (all of them for None).
    pub fn history(&self, sensor: &str, until: Option<f64>) -> Option<TemperatureHistory> {
        let inner = self.lock();
        let s = inner.sensors.get(sensor)?;
        Some(TemperatureHistory {
            samples: s
                .samples
                .iter()
                .copied()
                .filter(|(t, _)| until.is_none_or(|u| *t <= u))
                .collect(),
        })
    }

    /// (T_f, ∂T_f/∂τ) of the sensor's first-order lag with time constant `tau` (s) at its last
    /// sample at or before `time` (its newest sample for None).
    pub fn lagged(
        &self,
        sensor: &str,
        time: Option<f64>,
        tau: f64,
    ) -> Result<(f64, f64), LagUnavailable> {
        if !(tau > 0.0 && tau.is_finite()) {
            return Err(LagUnavailable::BadTimeConstant);
        }
        let mut inner = self.lock();
        let series = inner
            .sensors
            .get_mut(sensor)
            .ok_or(LagUnavailable::UnknownSensor)?;
        let count = match time {
            Some(t) => series.samples.partition_point(|(ts, _)| *ts <= t),
            None => series.samples.len(),
        };
        if count == 0 {
            return Err(LagUnavailable::NoSampleYet {
                first: series.samples.front().map(|s| s.0),
            });
        }
        let k = count - 1;
        let tau_bits = tau.to_bits();
        let at = match series.lags.iter().position(|c| c.tau_bits == tau_bits) {
            Some(i) => i,
            None => {
                if series.lags.len() >= LAG_CACHES_PER_SENSOR {
                    series.lags.remove(0);
                }
                series.lags.push(LagCache {
                    tau_bits,
                    filter: FirstOrderLag::new(tau),
                    values: Vec::new(),
                });
                series.lags.len() - 1
            }
        };
        let last = series.lags.len() - 1;
        series.lags.swap(at, last);
        let cache = &mut series.lags[last];
        while cache.values.len() <= k {
            let (t, v) = series.samples[cache.values.len()];
            cache.filter.advance(t, v, 0.0);
            let (_, value, d, _) = cache.filter.output().expect("fed a sample just now");
            cache.values.push((value, d));
        }
        Ok(cache.values[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::first_order_lag::first_order_lag;

    fn history(n: usize) -> TemperatureHistory {
        TemperatureHistory {
            samples: (0..n)
                .map(|k| {
                    (
                        10.0 * k as f64,
                        20.0 + 3.0 * (1.0 - (-(k as f64) / 150.0).exp())
                            + 0.01 * (k as f64 * 0.3).sin(),
                    )
                })
                .collect(),
        }
    }

    #[test]
    fn lag_at_any_time_equals_the_filter_over_the_history_up_to_it() {
        let h = history(2000);
        let t = TemperatureTimeline::from_histories([("column", &h)]).unwrap();
        for (query, tau) in [
            (0.0, 1200.0),
            (55.0, 1200.0),
            (9_999.9, 600.0),
            (19_990.0, 1200.0),
            (1e9, 1200.0),
        ] {
            let until = TemperatureHistory {
                samples: h
                    .samples
                    .iter()
                    .copied()
                    .filter(|(ts, _)| *ts <= query)
                    .collect(),
            };
            let (tf, d) = t.lagged("column", Some(query), tau).unwrap();
            let (tf_ref, d_ref) = first_order_lag(&until, tau);
            assert_eq!(
                (tf.to_bits(), d.to_bits()),
                (tf_ref.to_bits(), d_ref.to_bits()),
                "at {query} s, τ {tau}"
            );
        }
        assert_eq!(
            t.lagged("column", None, 1200.0).unwrap(),
            first_order_lag(&h, 1200.0)
        );
    }

    #[test]
    fn growing_while_shared_keeps_earlier_instants() {
        let h = history(300);
        let t = std::sync::Arc::new(TemperatureTimeline::new());
        let mut at_100 = None;
        for (k, &(time, v)) in h.samples.iter().enumerate() {
            t.push("column", time, v).unwrap();
            if k == 100 {
                at_100 = Some(t.lagged("column", Some(time), 900.0).unwrap());
            }
        }
        assert_eq!(
            t.lagged("column", Some(1000.0), 900.0).unwrap(),
            at_100.unwrap()
        );
        assert_eq!(t.sample_count("column"), Some(300));
    }

    #[test]
    fn capacity_drops_the_oldest_and_restarts_the_lag_there() {
        let h = history(50);
        let t = TemperatureTimeline::with_capacity(20);
        for &(time, v) in &h.samples {
            t.push("column", time, v).unwrap();
        }
        assert_eq!(t.sample_count("column"), Some(20));
        let kept = TemperatureHistory {
            samples: h.samples[30..].to_vec(),
        };
        assert_eq!(
            t.lagged("column", None, 300.0).unwrap(),
            first_order_lag(&kept, 300.0)
        );
    }

    #[test]
    fn bad_samples_and_lookups_are_refused() {
        let t = TemperatureTimeline::new();
        t.push("column", 0.0, 20.0).unwrap();
        let e = t.push("column", 0.0, 22.0).unwrap_err();
        assert!(e.contains("column") && e.contains("strictly"), "{e}");
        assert!(t
            .push("column", 1.0, f64::NAN)
            .unwrap_err()
            .contains("not finite"));
        assert_eq!(t.sample_count("column"), Some(1));
        assert_eq!(
            t.lagged("head", None, 10.0),
            Err(LagUnavailable::UnknownSensor)
        );
        assert_eq!(
            t.lagged("column", Some(-1.0), 10.0),
            Err(LagUnavailable::NoSampleYet { first: Some(0.0) })
        );
        assert_eq!(
            t.lagged("column", None, 0.0),
            Err(LagUnavailable::BadTimeConstant)
        );
        t.add_sensor("head");
        assert_eq!(
            t.lagged("head", None, 10.0),
            Err(LagUnavailable::NoSampleYet { first: None })
        );
    }

    /// A 1 Hz thermocouple over 10 h: a daily swing, a warming ramp, 20 mK of noise.
    fn thermocouple(t: f64) -> f64 {
        20.0 + 1.5 * (2.0 * std::f64::consts::PI * t / 86_400.0).sin()
            + 0.8 * (1.0 - (-t / 7200.0).exp())
            + 0.02 * ((t * 12.9898).sin() * 43_758.545).fract()
    }

    #[test]
    fn a_coarsened_history_bounds_memory_and_keeps_the_lags_inside_the_full_rate_span() {
        let exact = TemperatureTimeline::new();
        let bounded = TemperatureTimeline::with_full_rate(3600.0);
        let hours = 10.0;
        let mut worst: f64 = 0.0;
        let mut worst_d: f64 = 0.0;
        for k in 0..(hours * 3600.0) as usize {
            let t = k as f64;
            exact.push("column", t, thermocouple(t)).unwrap();
            bounded.push("column", t, thermocouple(t)).unwrap();
            // asked as a node asks: at least half an hour inside the full-rate hour, every τ of
            // diagnose's grid and beyond
            if k % 1800 == 0 && k > 0 {
                for tau in [120.0, 960.0, 3840.0, 15_360.0, 30_000.0] {
                    for back in [0.0, 900.0, 1800.0] {
                        let at = (t - back).max(0.0);
                        let (a, da) = exact.lagged("column", Some(at), tau).unwrap();
                        let (b, db) = bounded.lagged("column", Some(at), tau).unwrap();
                        worst = worst.max((a - b).abs());
                        worst_d = worst_d.max((da - db).abs());
                    }
                }
            }
        }
        let held = bounded.sample_count("column").unwrap();
        // the last hour at 1 Hz (+ a batch not yet coarsened) and 9 h at one a minute
        println!(
            "samples held: {held} of {}; largest lag difference {worst:.2e} K, of ∂/∂τ {worst_d:.2e} K/s",
            exact.sample_count("column").unwrap()
        );
        assert!(held <= 3600 + 600 + 9 * 60 + 3, "{held} samples held");
        // against the thermocouple's own 20 mK of noise: a hundredth of a percent
        assert!(
            worst < 1e-4,
            "the coarsened history moved a lag by {worst} K"
        );
        assert!(
            worst_d < 1e-6,
            "the coarsened history moved ∂T_f/∂τ by {worst_d} K/s"
        );
        // the history stays in time order
        let h = bounded.history("column", None).unwrap();
        assert!(h.samples.windows(2).all(|w| w[1].0 > w[0].0));
    }
}
