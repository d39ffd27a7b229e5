//! `metrocell topic hz TOPIC`

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::QosChoice;

#[derive(clap::Args)]
pub struct HzArgs {
    /// Topic name
    topic: String,
    /// Message type (pkg/msg/Type); discovered when omitted
    #[arg(long = "type")]
    type_name: Option<String>,
    /// Number of most recent intervals the statistics use
    #[arg(short, long, default_value_t = 10000)]
    window: usize,
    /// Stop after this many reports (one per second)
    #[arg(long)]
    count: Option<u64>,
    /// QoS of the reader
    #[arg(long, value_enum, default_value = "sensor-data")]
    qos: QosChoice,
    /// Seconds to wait for the topic to be discovered (when --type is not given)
    #[arg(long, default_value_t = 10.0)]
    discovery_timeout: f64,
}

/// Rate statistics over a sliding window of inter-arrival intervals, as `ros2 topic hz` prints them.
#[derive(Debug, Default)]
pub struct RateWindow {
    last: Option<Instant>,
    intervals: VecDeque<f64>,
    capacity: usize,
}

#[derive(Debug, PartialEq)]
pub struct RateStats {
    pub rate_hz: f64,
    pub min_s: f64,
    pub max_s: f64,
    pub std_dev_s: f64,
    pub window: usize,
}

impl RateWindow {
    pub fn new(capacity: usize) -> Self {
        RateWindow {
            capacity: capacity.max(1),
            ..Default::default()
        }
    }

    pub fn arrival(&mut self, at: Instant) {
        if let Some(last) = self.last {
            if self.intervals.len() == self.capacity {
                self.intervals.pop_front();
            }
            self.intervals
                .push_back(at.duration_since(last).as_secs_f64());
        }
        self.last = Some(at);
    }

    pub fn stats(&self) -> Option<RateStats> {
        let n = self.intervals.len();
        if n == 0 {
            return None;
        }
        let mean = self.intervals.iter().sum::<f64>() / n as f64;
        let var = self
            .intervals
            .iter()
            .map(|d| (d - mean).powi(2))
            .sum::<f64>()
            / n as f64;
        Some(RateStats {
            rate_hz: if mean > 0.0 {
                1.0 / mean
            } else {
                f64::INFINITY
            },
            min_s: self.intervals.iter().cloned().fold(f64::INFINITY, f64::min),
            max_s: self.intervals.iter().cloned().fold(0.0, f64::max),
            std_dev_s: var.sqrt(),
            window: n + 1,
        })
    }
}

pub fn run(args: HzArgs) -> anyhow::Result<i32> {
    let mut node = super::cli_node("topic_hz")?;
    let type_name = match &args.type_name {
        Some(t) => super::known_type(t)?,
        None => super::known_type(&super::discover_type(
            &node,
            &args.topic,
            Duration::from_secs_f64(args.discovery_timeout),
        )?)?,
    };
    let sub = node.raw_subscription(&args.topic, &type_name, args.qos.profile())?;
    let token = node.shutdown_token();
    let mut window = RateWindow::new(args.window);
    let mut next_report = Instant::now() + Duration::from_secs(1);
    let mut reports = 0u64;
    while !token.is_triggered() && args.count.is_none_or(|n| reports < n) {
        while let Some(_msg) = sub.take()? {
            window.arrival(Instant::now());
        }
        if Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            reports += 1;
            match window.stats() {
                Some(s) => println!(
                    "average rate: {:.3}\n\tmin: {:.3}s max: {:.3}s std dev: {:.5}s window: {}",
                    s.rate_hz, s.min_s, s.max_s, s.std_dev_s, s.window
                ),
                None => println!("no new messages"),
            }
        }
        token.wait_timeout(Duration::from_millis(1));
    }
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_ten_hertz_stream() {
        let t0 = Instant::now();
        let mut w = RateWindow::new(100);
        for i in 0..21 {
            w.arrival(t0 + Duration::from_millis(100 * i));
        }
        let s = w.stats().unwrap();
        assert!((s.rate_hz - 10.0).abs() < 1e-9, "{s:?}");
        assert!(s.std_dev_s < 1e-9);
        assert_eq!(s.window, 21);
    }

    #[test]
    fn window_forgets_old_intervals() {
        let t0 = Instant::now();
        let mut w = RateWindow::new(3);
        let times = [0, 1000, 1100, 1200, 1300];
        for ms in times {
            w.arrival(t0 + Duration::from_millis(ms));
        }
        let s = w.stats().unwrap();
        assert!(
            (s.rate_hz - 10.0).abs() < 1e-9,
            "the 1 s gap must have left the window: {s:?}"
        );
        assert!((s.max_s - 0.1).abs() < 1e-9);
    }

    #[test]
    fn no_interval_no_stats() {
        let mut w = RateWindow::new(3);
        assert!(w.stats().is_none());
        w.arrival(Instant::now());
        assert!(w.stats().is_none());
    }
}
