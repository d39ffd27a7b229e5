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
    /// Most recently used last.
    lags: Vec<LagCache>,
}

#[derive(Debug, Default)]
struct Inner {
    capacity: Option<usize>,
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
        let capacity = inner.capacity;
        let series = inner.sensors.entry(sensor.to_string()).or_default();
        if let Some(&(last, _)) = series.samples.back() {
            if !(time > last) {
                return Err(format!("temperature sensor `{sensor}`: sample at {time} s does not come after the previous one at {last} s (times must increase strictly)"));
            }
        }
        if capacity.is_some_and(|c| series.samples.len() >= c) {
            series.samples.pop_front();
            series.lags.clear();
        }
        series.samples.push_back((time, temperature));
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
}
