//! `machine.servo:` — the twin's axes follow their command through seed 004's dynamics (the
//! paper's plant, its defects fixed: crates/kinematics `five_axis_dynamics`) and a position loop
//! (crates/kinematics `axis_servo`), instead of being where they are told. A simulation option:
//! models never read it, so what it does to the readings is physics a model may or may not have.
//!
//! ```yaml
//! machine:
//!   servo:                   # per linear axis, SI or with units
//!     x: {inertia: 2e-4 kg m^2, damping: 1e-3 N m s/rad, friction: 0.1, normal_force: 50 N,
//!         radius: 6.4 mm, kp: 2 N m/rad}          # lead: default the radius (a belt); kd: critical
//! ```
//!
//! What a recording then holds: on a move each axis lags its command by μ r N·lead / k_p; at rest
//! it sticks within that band on the side it came from, so readings at rest differ between
//! approaches from + and − (a reversal error, which a `backlash` term models).
//!
//! Convention (stated once, here): the displacement added to the true tool point is actual −
//! commanded travel of each linear axis, in the machine frame, as the terms' displacements are
//! (the tool relative to the workpiece moves with the axes; on a five-axis machine the table's
//! turn takes it into the workpiece frame like every machine-frame term). Cartesian and
//! five-axis machines' linear axes x, y, z (a five-axis Z is seed 004's power screw: `lead` =
//! r·tan λ); the rotary axes do not follow a servo here.

use std::collections::BTreeMap;

use metrocell_kinematics::axis_servo::{follow_together, ServoAxis, ServoState};
use metrocell_kinematics::five_axis_dynamics::{FrictionSign, LinearAxis};
use nalgebra::Vector3;

use crate::error::CellError;
use crate::program::Program;

pub use metrocell_model_file::cell_file::ServoSection;

/// The validated `machine.servo`: each declared axis's index (0 x, 1 y, 2 z) and its servo, in
/// the same order.
#[derive(Debug, Clone, PartialEq)]
pub struct FollowingAxes {
    index: Vec<usize>,
    servos: Vec<ServoAxis>,
}

impl FollowingAxes {
    /// None without the section; `cartesian` false: the family does not support it.
    pub fn from_section(
        s: Option<&BTreeMap<String, ServoSection>>,
        cartesian: bool,
    ) -> Result<Option<FollowingAxes>, CellError> {
        let Some(s) = s else { return Ok(None) };
        if !cartesian {
            return Err(CellError::invalid(
                "machine.servo",
                "is simulated for the linear axes of cartesian and five-axis machines only",
            ));
        }
        let (mut index_of, mut servos) = (Vec::new(), Vec::new());
        for (name, a) in s {
            let p = format!("machine.servo.{name}");
            let index = ["x", "y", "z"]
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| CellError::invalid(&p, "is not an axis: give x, y or z"))?;
            if !(a.friction >= 0.0 && a.friction.is_finite()) {
                return Err(CellError::OutOfRange {
                    path: format!("{p}.friction"),
                    value: a.friction,
                    reason: "must be ≥ 0 (a friction coefficient)".into(),
                });
            }
            let radius = a.radius.positive(&format!("{p}.radius"), "m")?;
            let plant = LinearAxis {
                inertia: a.inertia.positive(&format!("{p}.inertia"), "kg m^2")?,
                damping: a
                    .damping
                    .non_negative(&format!("{p}.damping"), "N m s/rad")?,
                mu: a.friction,
                normal_force: a
                    .normal_force
                    .non_negative(&format!("{p}.normal_force"), "N")?,
                drum_radius: radius,
                sign: FrictionSign::Standard,
            };
            let kp = a.kp.positive(&format!("{p}.kp"), "N m/rad")?;
            let kd =
                a.kd.as_ref()
                    .map(|k| k.non_negative(&format!("{p}.kd"), "N m s/rad"))
                    .transpose()?;
            let lead = match &a.lead {
                Some(l) => l.positive(&format!("{p}.lead"), "m/rad")?,
                None => radius,
            };
            index_of.push(index);
            servos.push(ServoAxis::new(plant, lead, kp, kd));
        }
        Ok(Some(FollowingAxes {
            index: index_of,
            servos,
        }))
    }

    /// Each declared axis's dead band μ r N·lead / k_p (m): the lag on a steady move, the
    /// half-width of where it sticks at rest.
    pub fn dead_bands(&self) -> Vec<(usize, f64)> {
        self.index
            .iter()
            .zip(&self.servos)
            .map(|(i, a)| (*i, a.dead_band()))
            .collect()
    }
}

/// Where the axes are: their servo states at time `t`, advanced along the program as the
/// simulation asks for later instants.
#[derive(Debug, Clone)]
pub struct Following {
    t: f64,
    states: Vec<ServoState>,
}

impl Following {
    /// At rest where the program starts, at t = 0.
    pub fn new(axes: &FollowingAxes, program: &Program) -> Following {
        let home = program.state_at(0.0).q;
        Following {
            t: 0.0,
            states: axes
                .index
                .iter()
                .zip(&axes.servos)
                .map(|(i, a)| a.at_rest(home[*i]))
                .collect(),
        }
    }

    /// Actual − commanded travel of each axis at `t` (m; zero for an axis without a servo),
    /// integrating from the last instant asked (instants before it return its state).
    pub fn displacement(
        &mut self,
        axes: &FollowingAxes,
        program: &Program,
        t: f64,
    ) -> Vector3<f64> {
        if t > self.t {
            follow_together(&axes.servos, &mut self.states, self.t, t, |tau, travels| {
                let q = program.state_at(tau).q;
                for (travel, i) in travels.iter_mut().zip(&axes.index) {
                    *travel = q[*i];
                }
            });
            self.t = t;
        }
        let now = program.state_at(self.t).q;
        let mut d = Vector3::zeros();
        for ((i, a), s) in axes.index.iter().zip(&axes.servos).zip(&self.states) {
            d[*i] = a.travel(s) - now[*i];
        }
        d
    }
}
