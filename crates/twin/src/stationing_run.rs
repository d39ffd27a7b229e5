//! The samples of a stationing recording ([`crate::stationing`]): for each waypoint, in the
//! middle of its dwell (the program's timeline: moves at `rotary_rate`/`feed_rate`, `dwell` at
//! each waypoint, one pass), in this order and with one time stamp — the import layout's row:
//!
//! 1. the machine state (commanded joints, velocity 0; actual = commanded + the true
//!    `joint_offset`s: an encoder does not see a joint's gravity deflection);
//! 2. the instrument's point: the shared forward model at the true parameters (the cell's terms,
//!    then `tracker_pose[<setup>]` and `base_tilt`), its [`Signals`] carrying the ground's
//!    gravity in the base, the waypoint's setup, the time and the true temperatures; noise
//!    N(0, σ²) per axis;
//! 3. each accelerometer's reading (`AccelerometerSpec::reading` + noise);
//! 4. each thermocouple's reading (true temperature + offset + noise).
//!
//! Deterministic in the seed: each noise source draws from its own stream ([`crate::noise`]).

use std::collections::VecDeque;
use std::sync::Arc;

use metrocell_model::{ForwardModel, KinematicTruth};
use metrocell_physics::{PhysicsError, Signals};
use nalgebra::{Matrix3, Vector3};

use crate::noise::{stream, NoiseStream};
use crate::sample::*;
use crate::simulation::Simulation;
use crate::stationing::Stationing;
use crate::thermal_stepper::ThermalStepper;

/// One waypoint's samples, their truths and, for the instrument's point, the model's signals.
pub(crate) type Event = (Sample, SampleTruth, Option<Signals>);

/// The stream of a stationing recording (module doc).
pub(crate) struct StationingStream<'a> {
    sim: &'a Simulation,
    st: &'a Stationing,
    model: ForwardModel<'a>,
    params: Vec<f64>,
    kinematics: KinematicTruth,
    /// (measurement time, waypoint index), in time order, before the end of the run.
    schedule: Vec<(f64, usize)>,
    next: usize,
    queue: VecDeque<Event>,
    thermal: ThermalStepper,
    tc_slots: Vec<usize>,
    tc_noise: Vec<NoiseStream>,
    tc_names: Vec<Arc<str>>,
    point_noise: NoiseStream,
    accel_noise: Vec<NoiseStream>,
    joint_names: Arc<[String]>,
    setup_names: Vec<Arc<str>>,
    pub(crate) error: Option<PhysicsError>,
}

impl<'a> StationingStream<'a> {
    pub(crate) fn new(sim: &'a Simulation, st: &'a Stationing) -> Self {
        let cell = sim.cell();
        let seed = sim.seed();
        let model = sim.forward_model();
        let params = model.params();
        let kinematics = model
            .kinematic_truth(&params)
            .expect("the parameter vector is the model's own");
        let thermal = ThermalStepper::new(&cell.thermal, cell.thermal_step, seed);
        let tc_slots = cell
            .thermocouples
            .iter()
            .map(|t| thermal.slot_of_node(t.node.as_deref()))
            .collect();
        Self {
            sim,
            st,
            model,
            params,
            kinematics,
            schedule: measurement_times(sim),
            next: 0,
            queue: VecDeque::new(),
            thermal,
            tc_slots,
            tc_noise: (0..cell.thermocouples.len())
                .map(|i| NoiseStream::new(seed, stream::THERMOCOUPLE_BASE + i as u64))
                .collect(),
            tc_names: cell
                .thermocouples
                .iter()
                .map(|t| Arc::from(t.name.as_str()))
                .collect(),
            point_noise: NoiseStream::new(seed, stream::STATION_POINT),
            accel_noise: (0..st.accelerometers.len())
                .map(|i| NoiseStream::new(seed, stream::ACCELEROMETER_BASE + i as u64))
                .collect(),
            joint_names: cell.machine.joint_names().into(),
            setup_names: st
                .placements
                .iter()
                .map(|p| Arc::from(p.name.as_str()))
                .collect(),
            error: None,
        }
    }

    /// The next event, or None at the end of the run (or after an error, in `error`).
    pub(crate) fn next_event(&mut self) -> Option<Event> {
        if self.queue.is_empty() && self.error.is_none() {
            let (t, i) = *self.schedule.get(self.next)?;
            self.next += 1;
            if let Err(e) = self.waypoint(t, i) {
                self.error = Some(e);
            }
        }
        self.queue.pop_front()
    }

    /// The signals of waypoint `i` at `t`: time, true temperatures, gravity, setup.
    fn signals(&mut self, t: f64, q: &[f64], setup: Arc<str>, temperatures: &[f64]) -> Signals {
        let mut s = Signals {
            time: Some(t),
            gravity: Some(self.st.gravity()),
            setup: Some(setup),
            ..Signals::default()
        };
        for (tc, v) in self.sim.cell().thermocouples.iter().zip(temperatures) {
            s.temperatures.insert(tc.name.clone(), *v);
        }
        let n = q.len();
        self.model
            .set_motion(&mut s, q, &vec![0.0; n], &vec![1.0; n]);
        s
    }

    /// Queue the samples of waypoint `i`, measured at `t` (module doc for the order).
    fn waypoint(&mut self, t: f64, i: usize) -> Result<(), PhysicsError> {
        let (cell, st) = (self.sim.cell(), self.st);
        let w = &st.waypoints[i];
        let q = w.q.as_slice();
        let temperatures: Vec<f64> = self
            .tc_slots
            .iter()
            .map(|slot| self.thermal.at(*slot, t))
            .collect();
        let mut s = self.signals(t, q, self.setup_names[w.setup].clone(), &temperatures);
        let tool = self
            .model
            .tool_state(&self.params, &self.kinematics, q, &mut s, None)?;
        let prediction = self.model.tracker(&self.params, &tool, &mut s)?;
        // the machine state: what the controller commanded and what its encoders read
        let mut actual = q.to_vec();
        if let KinematicTruth::Arm { joint_offsets, .. } = &self.kinematics {
            actual
                .iter_mut()
                .zip(joint_offsets)
                .for_each(|(a, o)| *a += o);
        }
        let machine = MachineStateSample {
            t,
            names: self.joint_names.clone(),
            commanded: q.to_vec(),
            commanded_velocity: vec![0.0; q.len()],
            actual,
        };
        self.queue.push_back((
            Sample::MachineState(machine),
            SampleTruth::MachineState {
                displacement: tool.d,
            },
            None,
        ));
        // the instrument's point, with its noise
        let sigma = st.point_noise;
        let noise = Vector3::new(
            self.point_noise.normal(),
            self.point_noise.normal(),
            self.point_noise.normal(),
        ) * sigma;
        let point = StationPointSample {
            t,
            point_id: w.point_id.clone(),
            role: w.role,
            setup: self.setup_names[w.setup].clone(),
            measured: prediction.point + noise,
            covariance: Matrix3::identity() * (sigma * sigma),
            nominal: tool.nominal.translation.vector,
        };
        let tool_point = tool.target();
        let truth = SampleTruth::StationPoint {
            tool_point,
            levelled: st.levelling() * tool_point,
            point: prediction.point,
            joints: q.to_vec(),
        };
        self.queue
            .push_back((Sample::StationPoint(point), truth, Some(s)));
        // the accelerometers at rest
        let g = st.gravity();
        for (a, rng) in st.accelerometers.iter().zip(&mut self.accel_noise) {
            let clean = a.reading(&g);
            let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * a.noise;
            let sample = AccelerationSample {
                t,
                sensor: Arc::from(a.name.as_str()),
                link: Arc::from(a.link.as_str()),
                specific_force: clean + noise,
                variance: a.noise * a.noise,
            };
            self.queue.push_back((
                Sample::Acceleration(sample),
                SampleTruth::Acceleration {
                    specific_force: clean,
                    gravity: g,
                },
                None,
            ));
        }
        for (k, tc) in cell.thermocouples.iter().enumerate() {
            let noise = if tc.noise > 0.0 {
                tc.noise * self.tc_noise[k].normal()
            } else {
                0.0
            };
            let sample = TemperatureSample {
                t,
                sensor: self.tc_names[k].clone(),
                value: temperatures[k] + tc.offset + noise,
                variance: tc.noise * tc.noise
                    + tc.calibration_uncertainty * tc.calibration_uncertainty,
            };
            self.queue.push_back((
                Sample::Temperature(sample),
                SampleTruth::Temperature {
                    true_value: temperatures[k],
                },
                None,
            ));
        }
        Ok(())
    }
}

/// When each waypoint is measured: the middle of its dwell in the program's one pass, the ones
/// before the end of the run.
fn measurement_times(sim: &Simulation) -> Vec<(f64, usize)> {
    let program = &sim.cell().program;
    let Some(start) = program.cycle_start(0) else {
        return Vec::new();
    };
    program
        .segments
        .iter()
        .filter_map(|s| {
            s.dwell_point
                .map(|i| (start + s.start + 0.5 * program.dwell, i))
        })
        .filter(|(t, _)| *t < sim.duration())
        .collect()
}

/// The length of a stationing program's pass (s): its last waypoint's dwell ends before it.
pub fn stationing_length(program: &crate::program::Program) -> f64 {
    program.start + program.cycle_length()
}
