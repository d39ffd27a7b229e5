//! Seed 004's dynamic model of the five-axis prototype (eqs. 5–15), its defects fixed and the
//! paper's own behaviour kept behind a switch where it matters: five decoupled axes — Y and X
//! belt drives (a drum of radius r_m), Z a power screw with a flexible coupling, B a tilting
//! table that is a pendulum, C a rotary table — and the transmissions from motor angle to travel.
//!
//! SI throughout (rad, m, N, N·m, kg·m²). Fixes, stated once here:
//! - eq. 7 raises the derivative order (ω̈₂, ω̇₂): the X axis uses T_x = J₆ θ̈₂ + b₆ θ̇₂ + μ_s2 r_m N₂,
//!   the form of the paper's own section 4.4 ([`LinearAxis`] serves X and Y);
//! - eq. 8's "sgn" is 1 for ω > 0 and 0 otherwise, so friction vanishes when an axis runs
//!   backwards: [`FrictionSign::Standard`] (−1, 0, 1) is the physics, [`FrictionSign::AsPrinted`]
//!   reproduces the paper;
//! - eq. 15 calls λ the pitch; it is the lead angle (lead ℓ = 2π r tan λ), as eq. 10 uses it;
//! - section 4.4's T_B writes m l² where eq. 11 has m₂ l²: the table's mass ([`TiltTable`]).

/// How the friction coefficient follows the velocity (eqs. 8 and 10).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionSign {
    /// Coulomb friction opposing the motion: sgn ∈ {−1, 0, 1}.
    Standard,
    /// The paper's sgn: 1 for a positive velocity, 0 otherwise (no friction running backwards).
    AsPrinted,
}

impl FrictionSign {
    /// sgn(v) under this convention.
    pub fn of(self, v: f64) -> f64 {
        match self {
            FrictionSign::Standard => {
                if v > 0.0 {
                    1.0
                } else if v < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
            FrictionSign::AsPrinted => {
                if v > 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }
}

/// Eqs. 13–14: a belt's travel for a drum of pitch radius `r` turned by `theta`.
pub fn belt_travel(r: f64, theta: f64) -> f64 {
    r * theta
}

/// tan λ of a screw of `lead` (travel per turn) and pitch radius `r`: ℓ = 2π r tan λ.
pub fn screw_tan_lead_angle(lead: f64, r: f64) -> f64 {
    lead / (std::f64::consts::TAU * r)
}

/// Eq. 15: the nut's travel for the screw turned by `theta`.
pub fn screw_travel(r: f64, tan_lead_angle: f64, theta: f64) -> f64 {
    r * tan_lead_angle * theta
}

/// Eq. 10: ε = (μ_s3 − tan λ)/(1 + μ_s3 tan λ), μ_s3 = μ·sgn(θ̇₃).
pub fn screw_epsilon(mu: f64, tan_lead_angle: f64, velocity: f64, sign: FrictionSign) -> f64 {
    let mu_s = mu * sign.of(velocity);
    (mu_s - tan_lead_angle) / (1.0 + mu_s * tan_lead_angle)
}

/// Eq. 9 at steady state (θ̈₃ = θ̇₃ = 0 apart from the sign, θ₃ = θ_i, F₀ = T₀ = 0): the motor
/// torque holding an axial load `load` (N) on a screw of pitch radius `r`: T_z = r ε R.
pub fn screw_holding_torque(r: f64, epsilon: f64, load: f64) -> f64 {
    r * epsilon * load
}

/// A belt-driven linear axis (Y: eq. 5; X: eq. 7 fixed): J θ̈ + b θ̇ + μ_s r N = T.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearAxis {
    /// Inertia reflected to the motor (kg·m²).
    pub inertia: f64,
    /// Viscous damping (N·m·s/rad).
    pub damping: f64,
    /// Coulomb friction coefficient μ and the normal force N (N) it acts on.
    pub mu: f64,
    pub normal_force: f64,
    /// Drum pitch radius r_m (m).
    pub drum_radius: f64,
    pub sign: FrictionSign,
}

impl LinearAxis {
    /// θ̈ for torque `torque` at velocity `omega`.
    pub fn acceleration(&self, torque: f64, omega: f64) -> f64 {
        let friction = self.mu * self.sign.of(omega) * self.drum_radius * self.normal_force;
        (torque - friction - self.damping * omega) / self.inertia
    }

    /// The steady velocity under a constant torque, once moving in its direction.
    pub fn steady_velocity(&self, torque: f64) -> f64 {
        let direction = torque.signum();
        let friction = self.mu * self.sign.of(direction) * self.drum_radius * self.normal_force;
        (torque - friction) / self.damping
    }

    /// The velocity after `duration` s of constant `torque` from rest, by explicit Euler steps of
    /// `dt` (the paper gives no integrator; K8 pins this one).
    pub fn velocity_after(&self, torque: f64, duration: f64, dt: f64) -> f64 {
        let steps = (duration / dt).round() as usize;
        let mut omega = 0.0;
        for _ in 0..steps {
            // at rest, friction cannot exceed the drive: start in the torque's direction
            let moving = if omega == 0.0 { torque.signum() } else { omega };
            let friction = self.mu * self.sign.of(moving) * self.drum_radius * self.normal_force;
            omega += dt * (torque - friction - self.damping * omega) / self.inertia;
        }
        omega
    }
}

/// The tilting table (eq. 11): (m l² + I) θ̈ + m g l sin θ = T_B.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TiltTable {
    pub mass: f64,
    /// Bearing axis to the table's centre of mass (m).
    pub lever: f64,
    /// Inertia about the centre of mass (kg·m²).
    pub inertia: f64,
}

/// Standard gravity (m/s²), the digest's value.
pub const GRAVITY: f64 = 9.81;

impl TiltTable {
    /// I_eff = m l² + I (the parallel-axis term).
    pub fn effective_inertia(&self) -> f64 {
        self.mass * self.lever * self.lever + self.inertia
    }

    /// Small-oscillation natural frequency √(m g l / I_eff) (rad/s).
    pub fn natural_frequency(&self) -> f64 {
        (self.mass * GRAVITY * self.lever / self.effective_inertia()).sqrt()
    }

    /// The torque that holds the table still at `theta` (rad): m g l sin θ.
    pub fn holding_torque(&self, theta: f64) -> f64 {
        self.mass * GRAVITY * self.lever * theta.sin()
    }
}

/// The rotary table (eq. 12): I θ̈ = T_C; from rest under constant torque θ = T t²/(2 I).
pub fn rotary_angle_from_rest(inertia: f64, torque: f64, t: f64) -> f64 {
    torque * t * t / (2.0 * inertia)
}

/// Travel between two encoder samples at `feed` (m/s) sampled every `period` s, and whether a
/// feature of `size` m gets at least `min_samples` of them (K13: 150 ms logs of an 18 mm square).
pub fn sampling_adequate(feed: f64, period: f64, size: f64, min_samples: f64) -> (f64, bool) {
    let step = feed * period;
    (step, size / step >= min_samples)
}

#[cfg(test)]
// the digest's 0.318310 is this screw's tan λ (8 mm lead on a 4 mm radius: 1/π by coincidence),
// a figure to reproduce to its digits, not a stand-in for the constant
#[allow(clippy::approx_constant)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn k5_k6_transmissions() {
        // K5: GT2 20-tooth drum, r_m = 6.366 mm, one turn → 40.00 mm
        assert!(close(belt_travel(6.366e-3, TAU), 40.0e-3, 5e-6));
        // K6: r = 4 mm, lead 8 mm: tan λ = 0.318310, λ = 17.657°, one turn → 8.000 mm
        let t = screw_tan_lead_angle(8e-3, 4e-3);
        assert!(close(t, 0.318310, 5e-7));
        assert!(close(t.atan().to_degrees(), 17.657, 5e-4));
        assert!(close(screw_travel(4e-3, t, TAU), 8e-3, 1e-12));
    }

    #[test]
    fn k7_epsilon_under_each_sign_convention() {
        let t = screw_tan_lead_angle(8e-3, 4e-3);
        let e = |v: f64, s| screw_epsilon(0.15, t, v, s);
        assert!(close(e(1.0, FrictionSign::Standard), -0.160640, 5e-7));
        assert!(close(e(-1.0, FrictionSign::AsPrinted), -0.318310, 5e-7));
        assert!(close(e(0.0, FrictionSign::AsPrinted), -0.318310, 5e-7));
        assert!(close(e(-1.0, FrictionSign::Standard), -0.491791, 5e-7));
    }

    fn y_axis(sign: FrictionSign) -> LinearAxis {
        LinearAxis {
            inertia: 2e-4,
            damping: 1e-3,
            mu: 0.1,
            normal_force: 50.0,
            drum_radius: 0.0064,
            sign,
        }
    }

    #[test]
    fn k8_y_axis_step_reaches_its_steady_state() {
        let y = y_axis(FrictionSign::Standard);
        // friction torque μ r N = 0.032 N·m; ω_ss = 168 rad/s; τ = J/b = 0.2 s
        assert!(close(y.steady_velocity(0.2), 168.0, 1e-9));
        let w = y.velocity_after(0.2, 1.0, 1e-5);
        assert!(close(w, 166.868, 1e-3), "{w}");
        let analytic = 168.0 * (1.0 - (-5.0f64).exp());
        assert!(close(w, analytic, 1e-3));
        assert!(close(
            belt_travel(0.0064, y.steady_velocity(0.2)),
            1.0752,
            1e-9
        ));
    }

    #[test]
    fn k9_the_printed_sign_loses_friction_running_backwards() {
        assert!(close(
            y_axis(FrictionSign::AsPrinted).steady_velocity(-0.2),
            -200.0,
            1e-9
        ));
        assert!(close(
            y_axis(FrictionSign::Standard).steady_velocity(-0.2),
            -168.0,
            1e-9
        ));
    }

    #[test]
    fn k10_k11_tilt_and_rotary_tables() {
        let b = TiltTable {
            mass: 5.0,
            lever: 0.05,
            inertia: 0.02,
        };
        assert!(close(b.effective_inertia(), 0.0325, 1e-12));
        assert!(close(b.natural_frequency(), 8.6869, 5e-5));
        assert!(close(b.natural_frequency() / TAU, 1.3826, 5e-5));
        assert!(close(b.holding_torque(90f64.to_radians()), 2.4525, 1e-9));
        assert!(close(b.holding_torque(30f64.to_radians()), 1.22625, 1e-9));
        let c = rotary_angle_from_rest(0.05, 0.5, 0.2);
        assert!(close(c, 0.2, 1e-12) && close(c.to_degrees(), 11.459, 5e-4));
    }

    /// K12: with the fixed eq. 7, a torque that balances damping and friction holds ω constant
    /// (the printed form, with ω̈, would leave ω̇ free).
    #[test]
    fn k12_x_axis_torque_balance_holds_the_velocity() {
        let x = LinearAxis {
            inertia: 3e-4,
            damping: 2e-3,
            mu: 0.1,
            normal_force: 30.0,
            drum_radius: 0.0064,
            sign: FrictionSign::Standard,
        };
        let omega = 50.0;
        let torque = x.damping * omega + x.mu * x.drum_radius * x.normal_force;
        assert!(x.acceleration(torque, omega).abs() < 1e-12);
    }

    #[test]
    fn k13_k14_sampling_and_the_screw_under_a_drilling_load() {
        // 300 mm/min sampled every 150 ms: 0.75 mm a sample, 24 over the 18 mm side (≥ 20: marginal)
        let (step, ok) = sampling_adequate(0.3 / 60.0, 0.15, 0.018, 20.0);
        assert!(close(step, 0.75e-3, 1e-12) && ok);
        assert!(!sampling_adequate(0.3 / 60.0, 0.15, 0.012, 20.0).1);
        let t = screw_tan_lead_angle(8e-3, 4e-3);
        // creeping upward (θ̇ → 0⁺): μ_s3 = +0.15
        let creeping = screw_epsilon(0.15, t, 1e-9, FrictionSign::Standard);
        assert!(close(
            screw_holding_torque(0.004, creeping, 50.8),
            -0.032642,
            5e-7
        ));
        // exactly at rest with the paper's sgn(0) = 0
        let at_rest = screw_epsilon(0.15, t, 0.0, FrictionSign::AsPrinted);
        assert!(close(
            screw_holding_torque(0.004, at_rest, 50.8),
            -0.064681,
            5e-7
        ));
    }
}
