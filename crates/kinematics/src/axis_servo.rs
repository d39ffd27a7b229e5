//! A linear axis following its command: seed 004's plant (eqs. 5–7 as fixed in
//! [`crate::five_axis_dynamics`]: J θ̈ + b θ̇ + μ·sgn(θ̇)·r·N = T, the standard sign) driven by a
//! position loop with the damping fed forward,
//!
//!   T = k_p (θ_c − θ) + k_d (θ̇_c − θ̇) + b θ̇_c,   θ = travel / lead,
//!
//! the simplest loop a machine has (the paper gives none: its torques are inputs). What it
//! predicts, and why a verification sees it:
//! - on a move at constant velocity the axis lags its command by the friction the loop must
//!   overcome, e = μ r N / k_p (in travel: × lead) — the viscous part is fed forward;
//! - at rest it sticks where the loop's torque no longer beats the friction: within
//!   ±μ r N·lead / k_p of the command. Where in that band depends on how the move ended — a slow
//!   stop creeps in short of the command, a fast one overshoots (this loop brakes on the velocity
//!   error, and a command's velocity steps to zero) — and is the mirror image for a stop made
//!   the same way from the other side. Readings at rest therefore differ between approaches
//!   from + and from − by up to 2 μ r N·lead / k_p: a reversal error (ISO 230-2's B), the one
//!   `backlash` models, made by friction and stiffness instead of play, and of either sign.
//!
//! Convention (stated once): the following error is commanded − actual travel (m), positive when
//! the axis lags a move in +. Integration: semi-implicit Euler; at rest the axis holds while the
//! torque is within the friction (stiction), and a step that would reverse the velocity stops it.

use crate::five_axis_dynamics::LinearAxis;

/// One axis: the plant, its transmission, the loop's gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoAxis {
    /// J, b, μ, N, the friction radius r (`drum_radius`); its `sign` is not read (the standard
    /// sign is the physics).
    pub plant: LinearAxis,
    /// Travel per motor radian (m/rad): the drum's radius for a belt, r·tan λ for a screw (eq. 15).
    pub lead: f64,
    /// Position gain (N·m/rad).
    pub kp: f64,
    /// Velocity gain (N·m·s/rad).
    pub kd: f64,
}

/// The motor's angle (rad) and velocity (rad/s).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ServoState {
    pub theta: f64,
    pub omega: f64,
}

impl ServoAxis {
    /// The axis with velocity gain `kd`, or (None) the one that damps the loop critically,
    /// 2√(k_p J) − b (≥ 0).
    pub fn new(plant: LinearAxis, lead: f64, kp: f64, kd: Option<f64>) -> ServoAxis {
        let kd = kd.unwrap_or_else(|| (2.0 * (kp * plant.inertia).sqrt() - plant.damping).max(0.0));
        ServoAxis {
            plant,
            lead,
            kp,
            kd,
        }
    }

    /// The friction torque μ r N (N·m).
    pub fn friction(&self) -> f64 {
        self.plant.mu * self.plant.drum_radius * self.plant.normal_force
    }

    /// The half-width of the band an axis at rest sticks in, in travel (m): μ r N·lead / k_p —
    /// also the lag on a steady move.
    pub fn dead_band(&self) -> f64 {
        self.friction() / self.kp * self.lead
    }

    /// A step that keeps the integration stable and a stop's transient resolved: a fiftieth of
    /// the loop's time constant √(J/k_p), at most 1 ms (a stop lasts a few time constants, and
    /// where the axis sticks moves by about v·dt with the step).
    pub fn time_step(&self) -> f64 {
        (0.02 * (self.plant.inertia / self.kp).sqrt()).min(1e-3)
    }

    /// At rest at `travel` (m).
    pub fn at_rest(&self, travel: f64) -> ServoState {
        ServoState {
            theta: travel / self.lead,
            omega: 0.0,
        }
    }

    /// The axis's travel (m).
    pub fn travel(&self, s: &ServoState) -> f64 {
        s.theta * self.lead
    }

    /// Advance `s` by `dt` toward the command: travel `command` (m) moving at `velocity` (m/s).
    pub fn step(&self, s: &mut ServoState, command: f64, velocity: f64, dt: f64) {
        let (theta_c, omega_c) = (command / self.lead, velocity / self.lead);
        let p = &self.plant;
        let torque =
            self.kp * (theta_c - s.theta) + self.kd * (omega_c - s.omega) + p.damping * omega_c;
        let friction = self.friction();
        if s.omega == 0.0 && torque.abs() <= friction {
            return; // stuck: the loop's torque does not beat the friction
        }
        let direction = if s.omega != 0.0 {
            s.omega.signum()
        } else {
            torque.signum()
        };
        let omega =
            s.omega + dt * (torque - friction * direction - p.damping * s.omega) / p.inertia;
        // friction stops an axis; it never drives it backwards
        s.omega = if s.omega != 0.0 && omega.signum() != s.omega.signum() {
            0.0
        } else {
            omega
        };
        s.theta += dt * s.omega;
    }

    /// Follow `command(t) → travel` (m) from `s` at `from` to `to` (s): [`follow_together`] for
    /// one axis.
    pub fn follow(
        &self,
        s: &mut ServoState,
        from: f64,
        to: f64,
        mut command: impl FnMut(f64) -> f64,
    ) {
        follow_together(
            std::slice::from_ref(self),
            std::slice::from_mut(s),
            from,
            to,
            |t, out| out[0] = command(t),
        );
    }
}

/// Follow a command for several axes at once from `states` at `from` to `to` (s), in steps of
/// at most the smallest [`ServoAxis::time_step`]; `command(t, travels)` fills each axis's
/// commanded travel (m) at t — asked once a step for all of them (a machine's program is one
/// lookup for every axis). Each step commands the travel at its start and the mean velocity over
/// it, so a move that ends inside a step ends there in proportion (where a stop sticks does not
/// jump with the step's phase against the program's clock).
pub fn follow_together(
    axes: &[ServoAxis],
    states: &mut [ServoState],
    from: f64,
    to: f64,
    mut command: impl FnMut(f64, &mut [f64]),
) {
    if to <= from || axes.is_empty() {
        return;
    }
    let step = axes
        .iter()
        .map(ServoAxis::time_step)
        .fold(f64::INFINITY, f64::min);
    let n = ((to - from) / step).ceil().max(1.0);
    let dt = (to - from) / n;
    let (mut start, mut end) = (vec![0.0; axes.len()], vec![0.0; axes.len()]);
    command(from, &mut start);
    for k in 0..n as usize {
        command(from + (k + 1) as f64 * dt, &mut end);
        for (i, (a, s)) in axes.iter().zip(states.iter_mut()).enumerate() {
            a.step(s, start[i], (end[i] - start[i]) / dt, dt);
        }
        std::mem::swap(&mut start, &mut end);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::five_axis_dynamics::FrictionSign;

    /// K8's Y axis (J 2e-4 kg·m², b 1e-3 N·m·s/rad, μ 0.1, r 6.4 mm, N 50 N) on a belt, with a
    /// loop of k_p = 2 N·m/rad, critically damped.
    fn k8_axis() -> ServoAxis {
        let plant = LinearAxis {
            inertia: 2e-4,
            damping: 1e-3,
            mu: 0.1,
            normal_force: 50.0,
            drum_radius: 0.0064,
            sign: FrictionSign::Standard,
        };
        ServoAxis::new(plant, 0.0064, 2.0, None)
    }

    /// A move of `length` (m) at `speed` from `start`, then a dwell: the travel commanded at t.
    fn ramp(start: f64, length: f64, speed: f64) -> impl Fn(f64) -> f64 {
        let duration = length.abs() / speed;
        move |t: f64| {
            if t < duration {
                start + length.signum() * speed * t
            } else {
                start + length
            }
        }
    }

    #[test]
    fn a_steady_move_lags_by_the_friction_over_the_gain() {
        let a = k8_axis();
        // μ r N = 0.032 N·m; / k_p = 0.016 rad; × 6.4 mm = 102.4 µm
        assert!(
            (a.dead_band() - 102.4e-6).abs() < 1e-12,
            "{}",
            a.dead_band()
        );
        let mut s = a.at_rest(0.0);
        let command = ramp(0.0, 0.2, 0.02);
        a.follow(&mut s, 0.0, 5.0, &command);
        let lag = command(5.0) - a.travel(&s);
        assert!((lag - a.dead_band()).abs() < 1e-6, "lag {lag} m");
    }

    #[test]
    fn at_rest_it_sticks_within_the_band_mirrored_by_the_approach_short_when_slow_beyond_when_fast()
    {
        let a = k8_axis();
        let stop = |from: f64, length: f64, speed: f64| {
            let mut s = a.at_rest(from);
            a.follow(&mut s, 0.0, 20.0, ramp(from, length, speed));
            assert_eq!(s.omega, 0.0, "stopped");
            // commanded − actual
            from + length - a.travel(&s)
        };
        for (speed, short) in [(0.02, true), (0.05, false)] {
            let (e_plus, e_minus) = (stop(0.0, 0.1, speed), stop(0.2, -0.1, speed));
            assert!(
                e_plus.abs() <= a.dead_band() + 1e-9,
                "{speed} m/s: {e_plus}"
            );
            assert!(
                (e_plus + e_minus).abs() < 1e-9,
                "mirror images: {e_plus} {e_minus}"
            );
            assert_eq!(e_plus > 0.0, short, "{speed} m/s: {e_plus} m");
            assert!(e_plus.abs() > 0.2 * a.dead_band(), "{speed} m/s: {e_plus}");
        }
    }

    #[test]
    fn without_friction_it_settles_on_the_command() {
        let mut a = k8_axis();
        a.plant.mu = 0.0;
        let mut s = a.at_rest(0.0);
        a.follow(&mut s, 0.0, 20.0, ramp(0.0, 0.1, 0.02));
        assert!((a.travel(&s) - 0.1).abs() < 1e-9, "{}", a.travel(&s));
    }
}
