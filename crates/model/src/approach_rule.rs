//! The approach direction of an axis from its recorded commanded trajectory: the sign of its
//! last non-zero motion (what a reversal term such as `backlash` reads).
//!
//! Rule, per joint, applied sample by sample in time order:
//! * a recorded velocity beyond the velocity deadband is the motion at that instant: the
//!   direction is its sign;
//! * otherwise positions decide, with hysteresis: while moving positive the joint's extreme
//!   position is followed, and the direction turns negative only once the joint has come back
//!   more than the position deadband from that extreme (and symmetrically). Before the first
//!   motion beyond the deadband the direction is the configured initial one (unknown by
//!   default: `None`, never invented).
//!
//! Why a deadband, and why 1 nm (1 nrad) by default: commanded positions are exact in a
//! controller's log, but computed ones carry float rounding (a few 1e-16 relative, ≤ 1e-15 m
//! on a metre of travel) and an export printed with few decimals or re-scaled carries
//! quantisation; a rounding step must not count as a reversal. 1 nm is far above rounding and
//! far below any motion a metrology program makes between two commanded samples, and with the
//! hysteresis (the deadband is measured from the extreme, not per sample) even a creeping axis
//! is seen moving once it has gone 1 nm. Exports quantised coarser than that need a deadband
//! above their quantum (`SignalsBuilderOptions::approach_deadband`).

/// The approach state of one joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApproachTracker {
    /// +1, −1, or 0 = not known yet.
    direction: i8,
    /// The position the hysteresis is measured from (the extreme in the current direction).
    anchor: Option<f64>,
}

impl ApproachTracker {
    /// `initial`: the direction before any recorded motion (+1, −1), or None = unknown.
    pub fn new(initial: Option<f64>) -> Self {
        let direction = match initial {
            Some(d) if d > 0.0 => 1,
            Some(d) if d < 0.0 => -1,
            _ => 0,
        };
        Self {
            direction,
            anchor: None,
        }
    }

    /// The direction now: Some(±1.0), or None before any motion without an initial direction.
    pub fn direction(&self) -> Option<f64> {
        (self.direction != 0).then_some(self.direction as f64)
    }

    /// Take the next sample: position, and velocity if recorded (NaN or None: not recorded).
    pub fn update(
        &mut self,
        position: f64,
        velocity: Option<f64>,
        position_deadband: f64,
        velocity_deadband: f64,
    ) {
        if let Some(v) = velocity.filter(|v| v.is_finite() && v.abs() > velocity_deadband) {
            self.direction = if v > 0.0 { 1 } else { -1 };
            self.anchor = Some(position);
            return;
        }
        let Some(anchor) = self.anchor else {
            self.anchor = Some(position);
            return;
        };
        let d = position - anchor;
        match self.direction {
            1 if d > 0.0 => self.anchor = Some(position),
            -1 if d < 0.0 => self.anchor = Some(position),
            _ if d > position_deadband => {
                self.direction = 1;
                self.anchor = Some(position);
            }
            _ if d < -position_deadband => {
                self.direction = -1;
                self.anchor = Some(position);
            }
            _ => {}
        }
    }
}

/// The direction of the motion from `a` to `b` if it exceeds the deadband.
pub fn motion_sign(a: f64, b: f64, deadband: f64) -> Option<f64> {
    let d = b - a;
    if d > deadband {
        Some(1.0)
    } else if d < -deadband {
        Some(-1.0)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(positions: &[f64], initial: Option<f64>, db: f64) -> Vec<Option<f64>> {
        let mut t = ApproachTracker::new(initial);
        positions
            .iter()
            .map(|&p| {
                t.update(p, None, db, 1e-9);
                t.direction()
            })
            .collect()
    }

    #[test]
    fn sign_of_the_last_motion_held_through_dwells() {
        let d = run(&[0.0, 0.0, 0.1, 0.2, 0.2, 0.2, 0.1, 0.1, 0.1], None, 1e-9);
        assert_eq!(
            d,
            [
                None,
                None,
                Some(1.0),
                Some(1.0),
                Some(1.0),
                Some(1.0),
                Some(-1.0),
                Some(-1.0),
                Some(-1.0)
            ]
        );
        let homed = run(&[0.0, 0.0, -0.1], Some(1.0), 1e-9);
        assert_eq!(homed, [Some(1.0), Some(1.0), Some(-1.0)]);
    }

    #[test]
    fn rounding_jitter_is_not_a_reversal_but_a_creep_is_motion() {
        // +1 move, then rounding-level jitter around the end point: still +1
        let d = run(
            &[0.0, 0.3, 0.3 - 4e-17, 0.3 + 5e-17, 0.3 - 1e-16],
            None,
            1e-9,
        );
        assert!(d[1..].iter().all(|x| *x == Some(1.0)), "{d:?}");
        // a reversal creeping 0.4 nm per sample is seen once it has gone past 1 nm
        let creep: Vec<f64> = (0..6).map(|k| 0.3 - 0.4e-9 * k as f64).collect();
        let d = run(&[&[0.0][..], &creep[..]].concat(), None, 1e-9);
        assert_eq!(d[3], Some(1.0), "0.8 nm back: within the deadband");
        assert_eq!(d[4], Some(-1.0), "1.2 nm back: a reversal");
    }

    #[test]
    fn a_recorded_velocity_decides_at_its_instant() {
        let mut t = ApproachTracker::new(None);
        t.update(0.5, Some(0.0), 1e-9, 1e-9);
        assert_eq!(t.direction(), None);
        t.update(0.5, Some(-0.05), 1e-9, 1e-9);
        assert_eq!(
            t.direction(),
            Some(-1.0),
            "the move starts at this sample: its velocity says so before the position changes"
        );
        t.update(0.4, Some(f64::NAN), 1e-9, 1e-9);
        assert_eq!(t.direction(), Some(-1.0));
        assert_eq!(motion_sign(0.4, 0.4 + 2e-9, 1e-9), Some(1.0));
        assert_eq!(motion_sign(0.4, 0.4 - 5e-10, 1e-9), None);
    }
}
