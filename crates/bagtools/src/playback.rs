//! Timing of `bag play`: when each message is due on the wall clock, with a rate factor,
//! pause/resume and single steps. Pure (the caller passes `now`), so it is unit-tested.
//!
//! Convention: an *anchor* pairs a wall-clock instant with a bag log time; message `m` is due
//! at `anchor.wall + (m.log_time − anchor.log_time) / rate`. The first message and each stepped
//! message anchor the clock; a pause freezes bag time where it is and a resume re-anchors at
//! that bag time, so a pause shifts everything after it by the pause's length and gaps between
//! messages keep their recorded length ÷ rate.

use std::time::{Duration, Instant};

#[derive(Debug, Clone)]
pub struct PlaybackClock {
    rate: f64,
    anchor: Option<(Instant, u64)>,
    paused: bool,
}

impl PlaybackClock {
    /// `rate` > 0: 2.0 plays twice as fast as recorded.
    pub fn new(rate: f64) -> Self {
        assert!(
            rate > 0.0 && rate.is_finite(),
            "rate must be positive (checked by the caller)"
        );
        Self {
            rate,
            anchor: None,
            paused: false,
        }
    }

    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// How long to wait before publishing the message logged at `log_ns` (zero if due), or
    /// `None` while paused.
    pub fn wait_for(&mut self, log_ns: u64, now: Instant) -> Option<Duration> {
        if self.paused {
            return None;
        }
        let (wall, log0) = *self.anchor.get_or_insert((now, log_ns));
        let offset = Duration::from_secs_f64(log_ns.saturating_sub(log0) as f64 * 1e-9 / self.rate);
        Some((wall + offset).saturating_duration_since(now))
    }

    pub fn is_paused(&self) -> bool {
        self.paused
    }

    /// Pause at `now`: bag time (and `/clock`) stands still at the bag time of `now`.
    pub fn pause(&mut self, now: Instant) {
        if !self.paused {
            self.anchor = self.bag_time_at(now).map(|t| (now, t));
            self.paused = true;
        }
    }

    /// Resume at `now`: bag time goes on from where the pause froze it, so everything after the
    /// pause is shifted by the pause's length.
    pub fn resume(&mut self, now: Instant) {
        if self.paused {
            self.anchor = self.anchor.map(|(_, t)| (now, t));
            self.paused = false;
        }
    }

    pub fn toggle_pause(&mut self, now: Instant) {
        if self.paused {
            self.resume(now)
        } else {
            self.pause(now)
        }
    }

    /// A message logged at `log_ns` was published by a step (while paused) at `now`.
    pub fn stepped(&mut self, log_ns: u64, now: Instant) {
        self.anchor = Some((now, log_ns));
    }

    /// Start over (e.g. `--loop`): the next message re-anchors.
    pub fn restart(&mut self) {
        self.anchor = None;
    }

    /// Bag time (ns) corresponding to wall instant `now`, for `/clock`; `None` before the first
    /// message. While paused the clock stands at the bag time the pause froze.
    pub fn bag_time_at(&self, now: Instant) -> Option<u64> {
        let (wall, log0) = self.anchor?;
        if self.paused {
            return Some(log0);
        }
        Some(log0 + (now.saturating_duration_since(wall).as_secs_f64() * self.rate * 1e9) as u64)
    }
}

/// Parse `from:=to` remaps of `bag play --remap`.
pub fn parse_remap(s: &str) -> Result<(String, String), String> {
    match s.split_once(":=") {
        Some((a, b)) if !a.is_empty() && !b.is_empty() => Ok((a.to_string(), b.to_string())),
        _ => Err(format!("remap '{s}' is not of the form /from:=/to")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacing_is_divided_by_the_rate() {
        let t0 = Instant::now();
        let mut c = PlaybackClock::new(2.0);
        assert_eq!(c.wait_for(1_000_000_000, t0), Some(Duration::ZERO));
        assert_eq!(c.wait_for(3_000_000_000, t0), Some(Duration::from_secs(1)));
        assert_eq!(
            c.wait_for(3_000_000_000, t0 + Duration::from_millis(400)),
            Some(Duration::from_millis(600))
        );
        assert_eq!(
            c.bag_time_at(t0 + Duration::from_millis(500)),
            Some(2_000_000_000)
        );
    }

    #[test]
    fn pause_shifts_later_messages_and_step_reanchors() {
        let t0 = Instant::now();
        let mut c = PlaybackClock::new(1.0);
        c.wait_for(0, t0);
        c.pause(t0);
        assert_eq!(c.wait_for(100, t0), None);
        let t1 = t0 + Duration::from_secs(10);
        c.stepped(1_000_000_000, t1);
        c.resume(t1);
        // after resume bag time goes on from the stepped message (1 s): the one at 2 s waits 1 s
        assert_eq!(c.wait_for(2_000_000_000, t1), Some(Duration::from_secs(1)));
        assert_eq!(
            c.wait_for(2_500_000_000, t1),
            Some(Duration::from_millis(1500))
        );
    }

    #[test]
    fn remaps_parse() {
        assert_eq!(parse_remap("/a:=/b").unwrap(), ("/a".into(), "/b".into()));
        assert!(parse_remap("/a=/b").is_err());
    }

    #[test]
    fn a_pause_freezes_bag_time_and_shifts_what_follows() {
        let t0 = Instant::now();
        let s = Duration::from_secs;
        let mut c = PlaybackClock::new(1.0);
        assert_eq!(c.wait_for(10_000_000_000, t0), Some(Duration::ZERO));
        // Paused 4 s into the bag: /clock stays at bag time +4 s for the whole pause.
        c.pause(t0 + s(4));
        assert_eq!(c.bag_time_at(t0 + s(4)), Some(14_000_000_000));
        assert_eq!(c.bag_time_at(t0 + s(60)), Some(14_000_000_000));
        assert_eq!(c.wait_for(15_000_000_000, t0 + s(60)), None);
        // Resumed after 56 s: bag time goes on from +4 s, and a message logged at +5 s plays 1 s later.
        c.resume(t0 + s(60));
        assert_eq!(c.bag_time_at(t0 + s(60)), Some(14_000_000_000));
        assert_eq!(c.wait_for(15_000_000_000, t0 + s(60)), Some(s(1)));
    }
}
