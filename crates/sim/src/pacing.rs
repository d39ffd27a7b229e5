//! Real-time pacing of a live simulation: simulated time runs `speed` times faster than the
//! wall clock, both counted from the node's start.

use std::time::Duration;

/// Maps simulated seconds to wall-clock offsets and back at a fixed speed factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pacer {
    speed: f64,
}

impl Pacer {
    /// `speed` > 0 and finite (1 = real time, 100 = a hundred simulated seconds per second).
    pub fn new(speed: f64) -> Option<Pacer> {
        (speed > 0.0 && speed.is_finite()).then_some(Pacer { speed })
    }

    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Wall-clock offset at which simulated time `t` (s) is due.
    pub fn wall_offset(&self, t: f64) -> Duration {
        Duration::try_from_secs_f64(t.max(0.0) / self.speed).unwrap_or(Duration::MAX)
    }

    /// Simulated time reached after `elapsed` of wall-clock time.
    pub fn sim_time(&self, elapsed: Duration) -> f64 {
        elapsed.as_secs_f64() * self.speed
    }

    /// How far (s of wall time) publishing simulated time `t` at wall offset `elapsed` lags the
    /// schedule (0 when on time or early).
    pub fn lag(&self, t: f64, elapsed: Duration) -> f64 {
        (elapsed.as_secs_f64() - t / self.speed).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_scales_both_ways() {
        let p = Pacer::new(50.0).unwrap();
        assert_eq!(p.wall_offset(100.0), Duration::from_secs(2));
        assert_eq!(p.sim_time(Duration::from_millis(500)), 25.0);
        assert_eq!(p.lag(100.0, Duration::from_millis(2_500)), 0.5);
        assert_eq!(p.lag(100.0, Duration::from_millis(1_000)), 0.0);
    }

    #[test]
    fn bad_speeds_are_rejected() {
        assert!(Pacer::new(0.0).is_none());
        assert!(Pacer::new(-1.0).is_none());
        assert!(Pacer::new(f64::NAN).is_none());
        assert!(Pacer::new(f64::INFINITY).is_none());
    }
}
