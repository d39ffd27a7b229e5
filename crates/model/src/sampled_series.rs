//! Recorded streams as the signals builder reads them: a sampled scalar (linear interpolation
//! between samples no further apart than a maximum gap; nothing after the last sample, which
//! nothing brackets) and a state (the latest value at or before an instant). Times are integer nanoseconds
//! on the recording's clock, so interpolation fractions are exact ratios of integers — a float
//! epoch time (1.8e9 s) would only resolve 0.24 µs.

use std::collections::VecDeque;

/// A sampled scalar stream, strictly increasing in time.
#[derive(Debug, Clone, Default)]
pub struct SampledSeries {
    times: VecDeque<i64>,
    values: VecDeque<f64>,
}

impl SampledSeries {
    pub fn new() -> Self {
        Self::default()
    }

    /// Append a sample; refused (with the reason) when not after the last one or not finite.
    pub fn push(&mut self, t_ns: i64, value: f64) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("value {value} is not finite"));
        }
        if let Some(&last) = self.times.back() {
            if t_ns <= last {
                return Err(format!(
                    "sample at {t_ns} ns does not come after the previous one at {last} ns"
                ));
            }
        }
        self.times.push_back(t_ns);
        self.values.push_back(value);
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.times.len()
    }

    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    pub fn newest(&self) -> Option<i64> {
        self.times.back().copied()
    }

    pub fn oldest(&self) -> Option<i64> {
        self.times.front().copied()
    }

    /// The value at `t_ns`: the sample itself at a sample's time; between two samples at most
    /// `max_gap_ns` apart, the linear interpolation; otherwise (before the first sample, inside
    /// a longer gap, after the last sample) None.
    pub fn at(&self, t_ns: i64, max_gap_ns: i64) -> Option<f64> {
        let k = self.times.partition_point(|&ts| ts <= t_ns);
        if k == 0 {
            return None;
        }
        let (t0, v0) = (self.times[k - 1], self.values[k - 1]);
        if t0 == t_ns {
            return Some(v0);
        }
        match self.times.get(k) {
            Some(&t1) if t1 - t0 <= max_gap_ns => {
                let f = (t_ns - t0) as f64 / (t1 - t0) as f64;
                Some(v0 + (self.values[k] - v0) * f)
            }
            _ => None,
        }
    }

    /// Drop the samples before `t_ns`, keeping the last one before it (it brackets `t_ns`).
    pub fn forget_before(&mut self, t_ns: i64) {
        let k = self.times.partition_point(|&ts| ts < t_ns);
        for _ in 0..k.saturating_sub(1) {
            self.times.pop_front();
            self.values.pop_front();
        }
    }
}

/// A state stream (power-on instant, load): at an instant, the latest value received at or
/// before it; before the first message, that first message's value (a latched state received
/// after an instant describes a state that already held then).
#[derive(Debug, Clone)]
pub struct StateSeries<T> {
    entries: Vec<(i64, T)>,
}

impl<T> Default for StateSeries<T> {
    fn default() -> Self {
        Self {
            entries: Vec::new(),
        }
    }
}

impl<T: Clone> StateSeries<T> {
    /// Record a state received at `t_ns` (out-of-order ones are placed in time order).
    pub fn push(&mut self, t_ns: i64, value: T) {
        let k = self.entries.partition_point(|(ts, _)| *ts <= t_ns);
        self.entries.insert(k, (t_ns, value));
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn at(&self, t_ns: i64) -> Option<T> {
        let k = self.entries.partition_point(|(ts, _)| *ts <= t_ns);
        let i = k.saturating_sub(1);
        self.entries.get(i).map(|(_, v)| v.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_within_the_gap_and_never_past_the_samples() {
        let mut s = SampledSeries::new();
        s.push(1_000, 20.0).unwrap();
        s.push(2_000, 22.0).unwrap();
        s.push(10_000, 30.0).unwrap();
        assert_eq!(s.at(999, 5_000), None);
        assert_eq!(s.at(1_000, 5_000), Some(20.0));
        assert_eq!(s.at(1_250, 5_000), Some(20.5));
        assert_eq!(
            s.at(5_000, 5_000),
            None,
            "inside a gap longer than the maximum"
        );
        assert_eq!(
            s.at(10_000, 5_000),
            Some(30.0),
            "a sample's own time needs no neighbour"
        );
        assert_eq!(
            s.at(10_001, 5_000),
            None,
            "nothing brackets an instant after the last sample"
        );
        assert!(s
            .push(10_000, 1.0)
            .unwrap_err()
            .contains("does not come after"));
        assert!(s.push(11_000, f64::NAN).is_err());
        s.forget_before(9_000);
        assert_eq!((s.len(), s.oldest()), (2, Some(2_000)));
    }

    #[test]
    fn a_state_is_the_latest_at_or_before_or_the_first() {
        let mut s = StateSeries::default();
        assert_eq!(s.at(0), None::<f64>);
        s.push(100, 1.0);
        s.push(300, 3.0);
        s.push(200, 2.0);
        assert_eq!(
            (s.at(50), s.at(100), s.at(250), s.at(1_000)),
            (Some(1.0), Some(1.0), Some(2.0), Some(3.0))
        );
    }
}
