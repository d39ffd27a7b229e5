//! A rolling window of timed samples: what the drift fit and the plots read.
//!
//! Samples older than `window` seconds before the newest one are dropped, and so are the oldest
//! ones beyond `max_samples`, so memory stays flat over a shift whatever the rate. Times are
//! the messages' stamps [s since the Unix epoch] (sim time when the twin or a bag replay
//! publishes), never the wall clock of this process.

use std::collections::VecDeque;

use serde::Serialize;

use crate::trend::{fit_line, Trend};

#[derive(Clone, Debug)]
pub struct Series {
    window: f64,
    max_samples: usize,
    samples: VecDeque<(f64, f64)>,
}

/// Points for a plot: times relative to `t_end` [s] (≤ 0) and values.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PlotData {
    pub t: Vec<f64>,
    pub v: Vec<f64>,
}

impl Series {
    pub fn new(window: f64, max_samples: usize) -> Series {
        Series {
            window,
            max_samples: max_samples.max(3),
            samples: VecDeque::new(),
        }
    }

    /// Add a sample. A sample older than the newest one is kept in time order; one older than
    /// the window is ignored. Non-finite samples must be rejected by the caller.
    pub fn push(&mut self, t: f64, v: f64) {
        match self.samples.back() {
            Some(&(last, _)) if t < last => {
                if t < last - self.window {
                    return;
                }
                let at = self.samples.partition_point(|&(s, _)| s <= t);
                self.samples.insert(at, (t, v));
            }
            _ => self.samples.push_back((t, v)),
        }
        let newest = self.samples.back().map_or(t, |s| s.0);
        while self
            .samples
            .front()
            .is_some_and(|&(s, _)| s < newest - self.window)
            || self.samples.len() > self.max_samples
        {
            self.samples.pop_front();
        }
    }

    pub fn len(&self) -> usize {
        self.samples.len()
    }

    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    pub fn latest(&self) -> Option<(f64, f64)> {
        self.samples.back().copied()
    }

    /// Drift over the window (see [`crate::trend`]).
    pub fn trend(&self) -> Option<Trend> {
        fit_line(&self.samples)
    }

    /// At most `max_points` samples, evenly picked, the newest always included; times relative to `t_end`.
    pub fn plot(&self, t_end: f64, max_points: usize) -> PlotData {
        let n = self.samples.len();
        let step = n.div_ceil(max_points.max(1)).max(1);
        let mut out = PlotData::default();
        // count from the newest backwards so the latest sample is always shown
        let picked: Vec<&(f64, f64)> = self.samples.iter().rev().step_by(step).collect();
        for &&(t, v) in picked.iter().rev() {
            out.t.push(t - t_end);
            out.v.push(v);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_drops_old_samples_and_caps_the_count() {
        let mut s = Series::new(10.0, 1000);
        for k in 0..=30 {
            s.push(k as f64, k as f64);
        }
        // newest 30: keeps 20..=30
        assert_eq!(s.len(), 11);
        let mut c = Series::new(1e9, 5);
        for k in 0..100 {
            c.push(k as f64, 0.0);
        }
        assert_eq!((c.len(), c.latest()), (5, Some((99.0, 0.0))));
    }

    #[test]
    fn late_samples_are_inserted_in_order_or_ignored_when_too_old() {
        let mut s = Series::new(10.0, 100);
        s.push(0.0, 0.0);
        s.push(5.0, 5.0);
        s.push(20.0, 20.0); // evicts 0 and 5
        s.push(15.0, 15.0);
        s.push(2.0, 2.0); // older than the window
        let p = s.plot(20.0, 10);
        assert_eq!(p.t, vec![-5.0, 0.0]);
        assert_eq!(p.v, vec![15.0, 20.0]);
    }

    #[test]
    fn plot_thins_evenly_and_keeps_the_newest() {
        let mut s = Series::new(1e9, 10_000);
        for k in 0..1000 {
            s.push(k as f64, k as f64);
        }
        let p = s.plot(999.0, 100);
        assert_eq!(p.v.len(), 100);
        assert_eq!(*p.v.last().unwrap(), 999.0);
        assert_eq!(p.v[p.v.len() - 2], 989.0);
        assert_eq!(*p.t.last().unwrap(), 0.0);
    }
}
