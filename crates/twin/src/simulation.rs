//! The simulation: a cell, a duration and a seed → a time-ordered stream of typed samples.
//!
//! Streams are iterators with state independent of the duration (lazily advanced thermal model,
//! analytic program timeline, per-channel sample counters), so an 8-hour shift streams in flat
//! memory. Channels fire at t = k/rate (k = 0, 1, …) for t < duration; probe hits and camera
//! requests fire inside program dwells. Ties are broken in a fixed order: thermocouples (file
//! order), machine state, tracker, probe, camera.
//!
//! The tool state and every instrument's reading (tracker, probe, camera) come from the shared
//! forward model ([`metrocell_model::ForwardModel`]) at the true parameters: the cell's terms and
//! the instruments' terms ([`Cell::instrument_terms`]). The engine computes the signals
//! (commanded axis positions, approach directions and velocity from the program, the *true*
//! temperatures of the thermocouples' locations — the sensors' offsets and noise are concealed
//! from the physics, as in a real machine — and the weather station's readings), adds noise,
//! and schedules; nothing else. Terms with a first-order lag read the
//! true temperature history sampled every [`HISTORY_STEP`] (at most [`HISTORY_CAP`] samples, so
//! memory stays flat), held in one shared [`TemperatureTimeline`] that the signals of every
//! instant point to (`Signals::time` is the simulation time t, s since the start of the shift);
//! a term that reads nothing but histories is re-evaluated only when a history sample is added.

use std::sync::Arc;

use metrocell_camera_model::Distortion;
use metrocell_model::{DisplacementCache, ForwardModel, KinematicTruth, ProbeTarget, ToolState};
use metrocell_physics::instrument::edlen::shop_floor_refractivity;
use metrocell_physics::instrument::turbulence::range_scatter;
use metrocell_physics::model::TermModel;
use metrocell_physics::{PhysicsError, SignalKind, Signals, TemperatureTimeline, TermId};
use nalgebra::{DVector, Matrix3, Vector3};

use crate::cell::Cell;
use crate::error::CellError;
use crate::fiducial_plate::PLATE_MARKERS;
use crate::noise::{stream, NoiseStream};
use crate::program::MotionState;
use crate::sample::*;
use crate::stationing_run::StationingStream;
use crate::thermal_stepper::ThermalStepper;
use crate::tracker_model::{
    from_spherical, point_covariance, stated_range_sigma, BeamBreakProcess,
};

/// Spacing of the true temperature histories given to lagged terms (s).
pub const HISTORY_STEP: f64 = 10.0;
/// Longest history kept (samples); older samples are dropped (55 h at 10 s: ≫ any lag τ).
pub const HISTORY_CAP: usize = 20_000;

/// A configured simulation run.
#[derive(Debug)]
pub struct Simulation {
    cell: Cell,
    /// The instruments' terms at their true values ([`Cell::instrument_terms`]).
    instruments: TermModel,
    duration: f64,
    seed: u64,
}

/// The true parameters behind a simulation (for tests and reports).
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    /// Every true term parameter, `label.param` in term order.
    pub term_parameters: Vec<TrueParameter>,
    /// Tracker pose in the workpiece frame (translation m, Euler XYZ rad), if there is a tracker.
    pub tracker_translation: Option<Vector3<f64>>,
    pub tracker_euler_xyz: Option<[f64; 3]>,
    /// (A, B, τ) of the warm-up drift, if any.
    pub warmup: Option<(f64, f64, f64)>,
    /// Station biases (K, Pa, %RH).
    pub station_bias: Option<(f64, f64, f64)>,
    /// Thermocouple offsets by name (K).
    pub thermocouple_offsets: Vec<(String, f64)>,
    /// The instruments' terms' true parameters (`tracker_pose.tx`, …,
    /// `refraction.path_temperature_offset`, …, `probe_pretravel.mean`, `lens_distortion.k1`, …),
    /// named as an estimate names them; they follow `term_parameters` in the forward model's
    /// stacked vector.
    pub instrument_parameters: Vec<TrueParameter>,
}

impl Simulation {
    /// Check the run parameters and evaluate every true term once (so a term that cannot be
    /// evaluated is an error here, not in the middle of a stream).
    pub fn new(cell: Cell, duration: f64, seed: u64) -> Result<Self, CellError> {
        if !(duration > 0.0 && duration.is_finite()) {
            return Err(CellError::Simulation {
                reason: format!("duration must be > 0 s and finite, got {duration}"),
            });
        }
        // a stationing recording's instrument: a pose per setup (its tilt drawn with the seed)
        // and the ground's tilt
        let instruments = match &cell.stationing {
            Some(st) => st.instrument_terms(seed)?,
            None => cell.instrument_terms()?,
        };
        cell.forward_model(&instruments)
            .map_err(|err| CellError::Simulation {
                reason: format!("the forward model cannot be built: {err}"),
            })?;
        let sim = Simulation {
            cell,
            instruments,
            duration,
            seed,
        };
        let mut e = Engine::new(&sim);
        let ms = sim.cell.program.state_at(0.0);
        e.tool_state(0.0, &ms)
            .map_err(|err| CellError::Simulation {
                reason: format!("true terms cannot be evaluated: {err}"),
            })?;
        if let Some(st) = &sim.cell.stationing {
            let mut first = StationingStream::new(&sim, st);
            first.next_event();
            if let Some(err) = first.error {
                return Err(CellError::Simulation {
                    reason: format!("the first waypoint cannot be simulated: {err}"),
                });
            }
        }
        Ok(sim)
    }

    pub fn cell(&self) -> &Cell {
        &self.cell
    }
    pub fn duration(&self) -> f64 {
        self.duration
    }
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The instruments' terms at their true values ([`Cell::instrument_terms`]).
    pub fn instrument_terms(&self) -> &TermModel {
        &self.instruments
    }

    /// The shared forward model of this simulation (machine terms + instrument terms).
    pub fn forward_model(&self) -> ForwardModel<'_> {
        self.cell
            .forward_model(&self.instruments)
            .expect("checked by Simulation::new")
    }

    /// The signals the twin evaluates its model with at time t (temperatures, temperature
    /// histories, load, and the program's motion at t), computed afresh (cost grows with t:
    /// for tests and tools, not for streaming). The station's air and the tracker's time since
    /// power-on are the tracker sample's (`air_*`) and `t + powered_on_before_start`.
    pub fn signals_at(&self, t: f64) -> Signals {
        let mut e = Engine::new(self);
        let ms = self.cell.program.state_at(t);
        e.set_signals(t, &ms);
        e.signals
    }

    /// The sample stream (restarts from t = 0 on every call; deterministic in the seed).
    pub fn samples(&self) -> SampleStream<'_> {
        SampleStream {
            source: Source::new(self),
        }
    }

    /// The sample stream with the ground truth of each sample.
    pub fn samples_with_truth(&self) -> TruthStream<'_> {
        TruthStream {
            source: Source::new(self),
        }
    }

    /// The sample stream with, for every tracker reading and every stationing point, the
    /// [`Signals`] the shared model was evaluated with for it (time, commanded axis positions,
    /// velocities and approach directions, the true temperatures at the thermocouples' locations
    /// and the timeline of the lagged terms, the station's air of the reading, time since
    /// power-on, load; a stationing point's gravity and setup; `point` and `tracker_range` as the
    /// model set them). `None` for other samples.
    pub fn samples_with_signals(&self) -> SignalsStream<'_> {
        SignalsStream {
            source: Source::new(self),
        }
    }

    /// True parameters of the cell.
    pub fn ground_truth(&self) -> GroundTruth {
        let names = self.cell.terms.param_specs();
        let values = self.cell.terms.params();
        let tr = self.cell.tracker.as_ref();
        GroundTruth {
            term_parameters: names
                .into_iter()
                .zip(values)
                .map(|(s, v)| TrueParameter {
                    name: s.name,
                    value: v,
                    unit: s.unit,
                })
                .collect(),
            tracker_translation: tr.map(|t| t.pose.translation),
            tracker_euler_xyz: tr.map(|t| t.pose.euler_xyz),
            warmup: tr.and_then(|t| t.warmup.map(|w| (w.offset, w.amplitude, w.time_constant))),
            station_bias: tr.map(|t| {
                (
                    t.station.temperature_bias,
                    t.station.pressure_bias,
                    t.station.humidity_bias,
                )
            }),
            thermocouple_offsets: self
                .cell
                .thermocouples
                .iter()
                .map(|t| (t.name.clone(), t.offset))
                .collect(),
            instrument_parameters: self
                .instruments
                .param_specs()
                .into_iter()
                .zip(self.instruments.params())
                .map(|(s, v)| TrueParameter {
                    name: s.name,
                    value: v,
                    unit: s.unit,
                })
                .collect(),
        }
    }
}

/// Where a stream's samples come from: the periodic channels and dwells of a program, or a
/// stationing program's waypoints ([`crate::stationing_run`]).
enum Source<'a> {
    Engine(Box<Engine<'a>>),
    Stationing(Box<StationingStream<'a>>),
}

impl<'a> Source<'a> {
    fn new(sim: &'a Simulation) -> Self {
        match &sim.cell.stationing {
            Some(st) => Source::Stationing(Box::new(StationingStream::new(sim, st))),
            None => Source::Engine(Box::new(Engine::new(sim))),
        }
    }

    /// The next sample, its truth and (when `signals`) the model's signals of a reading.
    fn next(&mut self, signals: bool) -> Option<(Sample, SampleTruth, Option<Signals>)> {
        match self {
            Source::Engine(e) => {
                let (sample, truth) = e.next_event()?;
                let s =
                    (signals && matches!(sample, Sample::Tracker(_))).then(|| e.signals.clone());
                Some((sample, truth, s))
            }
            Source::Stationing(st) => st.next_event(),
        }
    }

    fn error(&self) -> Option<&PhysicsError> {
        match self {
            Source::Engine(e) => e.error.as_ref(),
            Source::Stationing(st) => st.error.as_ref(),
        }
    }
}

/// Iterator over samples (truth dropped). If a term fails mid-stream (not expected after
/// [`Simulation::new`]'s check) the stream ends and [`SampleStream::error`] says why.
pub struct SampleStream<'a> {
    source: Source<'a>,
}

impl SampleStream<'_> {
    pub fn error(&self) -> Option<&PhysicsError> {
        self.source.error()
    }
}

impl Iterator for SampleStream<'_> {
    type Item = Sample;
    fn next(&mut self) -> Option<Sample> {
        self.source.next(false).map(|(s, _, _)| s)
    }
}

/// Iterator over (sample, truth).
pub struct TruthStream<'a> {
    source: Source<'a>,
}

impl TruthStream<'_> {
    pub fn error(&self) -> Option<&PhysicsError> {
        self.source.error()
    }
}

impl Iterator for TruthStream<'_> {
    type Item = (Sample, SampleTruth);
    fn next(&mut self) -> Option<(Sample, SampleTruth)> {
        self.source.next(false).map(|(s, t, _)| (s, t))
    }
}

/// Iterator over (sample, the model's signals of a tracker reading or a stationing point).
pub struct SignalsStream<'a> {
    source: Source<'a>,
}

impl SignalsStream<'_> {
    pub fn error(&self) -> Option<&PhysicsError> {
        self.source.error()
    }
}

impl Iterator for SignalsStream<'_> {
    type Item = (Sample, Option<Signals>);
    fn next(&mut self) -> Option<(Sample, Option<Signals>)> {
        self.source.next(true).map(|(s, _, signals)| (s, signals))
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum ChannelKind {
    Thermocouple(usize),
    MachineState,
    Tracker,
}

struct Periodic {
    kind: ChannelKind,
    rate: f64,
    k: u64,
}

impl Periodic {
    fn next_t(&self) -> f64 {
        self.k as f64 / self.rate
    }
}

/// Walks the dwells of the program in time order, `per_dwell` events at given offsets.
struct DwellEvents {
    offsets: Vec<f64>,
    cycle: u32,
    dwell: usize,
    sub: usize,
    dwell_segments: Vec<usize>,
    done: bool,
}

struct DwellEvent {
    t: f64,
    cycle: u32,
    segment: usize,
    sub: usize,
}

impl DwellEvents {
    fn new(cell: &Cell, offsets: Vec<f64>) -> Self {
        let dwell_segments: Vec<usize> = cell
            .program
            .segments
            .iter()
            .enumerate()
            .filter(|(_, s)| s.dwell_point.is_some())
            .map(|(i, _)| i)
            .collect();
        let offsets: Vec<f64> = offsets
            .into_iter()
            .filter(|o| *o < cell.program.dwell)
            .collect();
        let done = offsets.is_empty() || dwell_segments.is_empty();
        Self {
            offsets,
            cycle: 0,
            dwell: 0,
            sub: 0,
            dwell_segments,
            done,
        }
    }
    fn peek(&self, cell: &Cell) -> Option<DwellEvent> {
        if self.done {
            return None;
        }
        let start = cell.program.cycle_start(self.cycle)?;
        let seg = self.dwell_segments[self.dwell];
        Some(DwellEvent {
            t: start + cell.program.segments[seg].start + self.offsets[self.sub],
            cycle: self.cycle,
            segment: seg,
            sub: self.sub,
        })
    }
    fn advance(&mut self) {
        self.sub += 1;
        if self.sub == self.offsets.len() {
            self.sub = 0;
            self.dwell += 1;
            if self.dwell == self.dwell_segments.len() {
                self.dwell = 0;
                self.cycle = match self.cycle.checked_add(1) {
                    Some(c) => c,
                    None => {
                        self.done = true;
                        0
                    }
                };
            }
        }
    }
}

struct TrackerState {
    noise: NoiseStream,
    station: NoiseStream,
    breaks: Option<BeamBreakProcess>,
}

struct Engine<'a> {
    sim: &'a Simulation,
    cell: &'a Cell,
    thermal: ThermalStepper,
    periodic: Vec<Periodic>,
    probe_events: Option<DwellEvents>,
    camera_events: Option<DwellEvents>,
    tc_noise: Vec<NoiseStream>,
    tc_slots: Vec<usize>,
    tc_names: Vec<Arc<str>>,
    tracker: Option<TrackerState>,
    probe_noise: NoiseStream,
    axis_names: Arc<[String]>,
    signals: Signals,
    /// The true temperature histories of the lagged terms (shared with `signals`).
    timeline: Arc<TemperatureTimeline>,
    /// (sensor name, thermal slot) of every history a term reads.
    history_sensors: Vec<(String, usize)>,
    /// Index of the next history sample (at history_k·HISTORY_STEP).
    history_k: u64,
    /// The shared forward model, the true stacked parameters, and a copy whose refraction
    /// parameters carry the weather station's noise of the current reading.
    model: ForwardModel<'a>,
    params: Vec<f64>,
    reading_params: Vec<f64>,
    /// Index of `refraction.path_temperature_offset` in the stacked vector.
    refraction_at: Option<usize>,
    /// The kinematic part of the truth (delta geometry, arm chain).
    kinematics: KinematicTruth,
    /// Displacements of the terms that read only histories, until a history grows.
    cache: DisplacementCache,
    /// The axes' servo states (`machine.servo`), advanced as the instants asked grow.
    following: Option<crate::following_error::Following>,
    error: Option<PhysicsError>,
}

impl<'a> Engine<'a> {
    fn new(sim: &'a Simulation) -> Self {
        let cell = &sim.cell;
        let seed = sim.seed;
        let thermal = ThermalStepper::new(&cell.thermal, cell.thermal_step, seed);
        let mut periodic: Vec<Periodic> = cell
            .thermocouples
            .iter()
            .enumerate()
            .map(|(i, t)| Periodic {
                kind: ChannelKind::Thermocouple(i),
                rate: t.rate,
                k: 0,
            })
            .collect();
        if let Some(r) = cell.machine_state_rate {
            periodic.push(Periodic {
                kind: ChannelKind::MachineState,
                rate: r,
                k: 0,
            });
        }
        if let Some(t) = &cell.tracker {
            periodic.push(Periodic {
                kind: ChannelKind::Tracker,
                rate: t.rate,
                k: 0,
            });
        }
        let probe_events = cell.probe.as_ref().map(|p| {
            DwellEvents::new(
                cell,
                (0..p.directions.len())
                    .map(|j| (j + 1) as f64 * p.hit_interval)
                    .collect(),
            )
        });
        let camera_events = cell
            .camera
            .as_ref()
            .map(|c| DwellEvents::new(cell, vec![c.delay]));
        let tc_slots = cell
            .thermocouples
            .iter()
            .map(|t| thermal.slot_of_node(t.node.as_deref()))
            .collect();
        let mut signals = Signals::default();
        for t in &cell.thermocouples {
            signals.temperatures.insert(t.name.clone(), 20.0);
        }
        signals.load_force = cell.load_force;
        let timeline = Arc::new(TemperatureTimeline::with_capacity(HISTORY_CAP));
        signals.timeline = Some(timeline.clone());
        let mut history_sensors: Vec<(String, usize)> = Vec::new();
        for t in &cell.terms.terms {
            for s in t.term.signals() {
                if let SignalKind::TemperatureHistory(name) = s {
                    if !history_sensors.iter().any(|(n, _)| n == &name) {
                        let node = cell
                            .thermocouples
                            .iter()
                            .find(|tc| tc.name == name)
                            .and_then(|tc| tc.node.as_deref());
                        history_sensors.push((name.clone(), thermal.slot_of_node(node)));
                        timeline.add_sensor(&name);
                    }
                }
            }
        }
        let model = sim.forward_model();
        let params = model.params();
        let kinematics = model
            .kinematic_truth(&params)
            .expect("the parameter vector is the model's own");
        Engine {
            sim,
            cell,
            thermal,
            periodic,
            probe_events,
            camera_events,
            tc_noise: (0..cell.thermocouples.len())
                .map(|i| NoiseStream::new(seed, stream::THERMOCOUPLE_BASE + i as u64))
                .collect(),
            tc_slots,
            tc_names: cell
                .thermocouples
                .iter()
                .map(|t| Arc::from(t.name.as_str()))
                .collect(),
            tracker: cell.tracker.as_ref().map(|t| TrackerState {
                noise: NoiseStream::new(seed, stream::TRACKER),
                station: NoiseStream::new(seed, stream::STATION),
                breaks: t.beam_breaks.map(|b| {
                    BeamBreakProcess::new(
                        NoiseStream::new(seed, stream::BEAM_BREAKS),
                        b.rate,
                        b.mean_duration,
                    )
                }),
            }),
            probe_noise: NoiseStream::new(seed, stream::PROBE),
            axis_names: Arc::from(cell.machine.joint_names()),
            signals,
            timeline,
            history_sensors,
            history_k: 0,
            cache: DisplacementCache::new(&model),
            following: cell
                .servo
                .as_ref()
                .map(|axes| crate::following_error::Following::new(axes, &cell.program)),
            kinematics,
            refraction_at: model.instrument_param_start(TermId::Refraction),
            reading_params: params.clone(),
            params,
            model,
            error: None,
        }
    }

    /// Append the true temperature of every history a term reads, on the HISTORY_STEP grid up
    /// to t (called in time order, before the thermal model is advanced past t by anything else).
    fn update_histories(&mut self, t: f64) {
        if !self.history_sensors.is_empty() && self.history_k as f64 * HISTORY_STEP <= t {
            while self.history_k as f64 * HISTORY_STEP <= t {
                let th = self.history_k as f64 * HISTORY_STEP;
                for (name, slot) in &self.history_sensors {
                    let v = self.thermal.at(*slot, th);
                    // times advance on the grid and the thermal model is finite: cannot fail
                    let _ = self.timeline.push(name, th, v);
                }
                self.history_k += 1;
            }
            self.cache.invalidate();
        }
    }

    /// Signals at t for the motion state: time, histories up to t, motion, true temperatures.
    fn set_signals(&mut self, t: f64, ms: &MotionState) {
        self.update_histories(t);
        self.signals.time = Some(t);
        self.model.set_motion(
            &mut self.signals,
            ms.q.as_slice(),
            ms.velocity.as_slice(),
            &ms.approach,
        );
        for (i, tc) in self.cell.thermocouples.iter().enumerate() {
            let v = self.thermal.at(self.tc_slots[i], t);
            if let Some(x) = self.signals.temperatures.get_mut(&tc.name) {
                *x = v;
            }
        }
    }

    /// The tool at t for the motion state (the shared model at the true parameters, plus the
    /// cell's test-only `disturbances`, which no model knows).
    fn tool_state(&mut self, t: f64, ms: &MotionState) -> Result<ToolState, PhysicsError> {
        self.set_signals(t, ms);
        let mut tool = self.model.tool_state(
            &self.params,
            &self.kinematics,
            ms.q.as_slice(),
            &mut self.signals,
            Some(&mut self.cache),
        )?;
        // a machine-frame displacement: into the frame tool points are reported in (a five-axis
        // table turns it; the identity elsewhere)
        let delta = self.beyond_the_terms(t, ms);
        tool.truth.translation.vector += tool.nominal.rotation * delta;
        tool.d += delta;
        Ok(tool)
    }

    /// What moves the tool besides the model's terms at t, machine frame: the axes' following
    /// error (`machine.servo`) and the test-only disturbances.
    fn beyond_the_terms(&mut self, t: f64, ms: &MotionState) -> Vector3<f64> {
        let mut delta = Vector3::zeros();
        if !self.cell.disturbances.is_empty() {
            delta += self.cell.disturbances.displacement(t, &v3(&ms.q));
        }
        if let (Some(axes), Some(f)) = (&self.cell.servo, self.following.as_mut()) {
            delta += f.displacement(axes, &self.cell.program, t);
        }
        delta
    }

    fn next_event(&mut self) -> Option<(Sample, SampleTruth)> {
        if self.error.is_some() {
            return None;
        }
        // Earliest channel; ties by channel order (periodic in construction order, probe, camera).
        let mut best: Option<(f64, usize)> = None;
        for (i, c) in self.periodic.iter().enumerate() {
            let t = c.next_t();
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, i));
            }
        }
        let n = self.periodic.len();
        if let Some(ev) = self.probe_events.as_ref().and_then(|p| p.peek(self.cell)) {
            if best.is_none_or(|(bt, _)| ev.t < bt) {
                best = Some((ev.t, n));
            }
        }
        if let Some(ev) = self.camera_events.as_ref().and_then(|p| p.peek(self.cell)) {
            if best.is_none_or(|(bt, _)| ev.t < bt) {
                best = Some((ev.t, n + 1));
            }
        }
        let (t, which) = best?;
        if t >= self.sim.duration {
            return None;
        }
        self.update_histories(t);
        let out = if which < n {
            self.periodic[which].k += 1;
            match self.periodic[which].kind {
                ChannelKind::Thermocouple(i) => Ok(self.thermocouple(i, t)),
                ChannelKind::MachineState => self.machine_state(t),
                ChannelKind::Tracker => self.tracker_sample(t),
            }
        } else if which == n {
            let ev = self.probe_events.as_ref().and_then(|p| p.peek(self.cell))?;
            self.probe_events.as_mut()?.advance();
            self.probe_hit(ev)
        } else {
            let ev = self
                .camera_events
                .as_ref()
                .and_then(|p| p.peek(self.cell))?;
            self.camera_events.as_mut()?.advance();
            self.camera_request(ev)
        };
        match out {
            Ok(v) => Some(v),
            Err(e) => {
                self.error = Some(e);
                None
            }
        }
    }

    fn thermocouple(&mut self, i: usize, t: f64) -> (Sample, SampleTruth) {
        let spec = &self.cell.thermocouples[i];
        let truth = self.thermal.at(self.tc_slots[i], t);
        let noise = if spec.noise > 0.0 {
            spec.noise * self.tc_noise[i].normal()
        } else {
            0.0
        };
        let s = TemperatureSample {
            t,
            sensor: self.tc_names[i].clone(),
            value: truth + spec.offset + noise,
            variance: spec.noise * spec.noise
                + spec.calibration_uncertainty * spec.calibration_uncertainty,
        };
        (
            Sample::Temperature(s),
            SampleTruth::Temperature { true_value: truth },
        )
    }

    fn machine_state(&mut self, t: f64) -> Result<(Sample, SampleTruth), PhysicsError> {
        let ms = self.cell.program.state_at(t);
        let d = self.tool_state(t, &ms)?.d;
        // actual: cartesian/delta and the five-axis linear axes commanded + d; rotary axes as
        // commanded; an arm's joints at commanded + their true zero offsets.
        let mut actual = ms.q.as_slice().to_vec();
        match &self.kinematics {
            KinematicTruth::Arm { joint_offsets, .. } => actual
                .iter_mut()
                .zip(joint_offsets)
                .for_each(|(a, o)| *a += o),
            _ => (0..3).for_each(|k| actual[k] += d[k]),
        }
        let s = MachineStateSample {
            t,
            names: self.axis_names.clone(),
            commanded: ms.q.as_slice().to_vec(),
            commanded_velocity: ms.velocity.as_slice().to_vec(),
            actual,
        };
        Ok((
            Sample::MachineState(s),
            SampleTruth::MachineState { displacement: d },
        ))
    }

    fn tracker_sample(&mut self, t: f64) -> Result<(Sample, SampleTruth), PhysicsError> {
        let spec = self
            .cell
            .tracker
            .as_ref()
            .expect("tracker channel exists only with a tracker");
        let ms = self.cell.program.state_at(t);
        let tool = self.tool_state(t, &ms)?;
        // the tracker sights the tool relative to the part (truth − d_w, crates/model `forward`)
        let (nominal_point, tool_point, d) =
            (tool.nominal.translation.vector, tool.target(), tool.d);
        // air: truth on the beam vs the station's reading
        let ambient = self.thermal.ambient(t);
        let air = self.cell.air;
        let st = &spec.station;
        let state = self
            .tracker
            .as_mut()
            .expect("tracker state exists with a tracker");
        let mut station_noise = |sigma: f64| {
            if sigma > 0.0 {
                sigma * state.station.normal()
            } else {
                0.0
            }
        };
        let (noise_t, noise_p, noise_h) = (
            station_noise(st.temperature_noise),
            station_noise(st.pressure_noise),
            station_noise(st.humidity_noise),
        );
        let t_station = ambient + st.temperature_bias + noise_t;
        let p_station = air.pressure + st.pressure_bias + noise_p;
        let h_station = air.humidity + st.humidity_bias + noise_h;
        let n_true = shop_floor_refractivity(
            air.pressure,
            ambient + air.beam_temperature_offset,
            air.humidity,
        );
        let n_station = shop_floor_refractivity(p_station, t_station, h_station);
        // The refraction term's path offsets are relative to the station's reading, so this
        // reading's station noise moves them (the beam's air does not see the station's noise).
        if let Some(r) = self.refraction_at {
            self.reading_params[r] = self.params[r] - noise_t;
            self.reading_params[r + 1] = self.params[r + 1] - noise_p;
        }
        let s = &mut self.signals;
        (s.air_temperature, s.air_pressure, s.air_humidity) =
            (Some(t_station), Some(p_station), Some(h_station));
        s.time_since_power_on = Some(t + spec.powered_on_before_start);
        let prediction = self.model.tracker(&self.reading_params, &tool, s)?;
        let (x, rho, az, el) = (
            prediction.point,
            prediction.range,
            prediction.azimuth,
            prediction.elevation,
        );
        let (refraction, warmup) = (prediction.refraction, prediction.warmup);
        let c = spec
            .turbulence
            .iter()
            .filter(|w| t >= w.start && t < w.end)
            .map(|w| w.coefficient)
            .fold(0.0, f64::max);
        let sigma_eff = range_scatter(
            spec.range_noise_constant,
            spec.range_noise_per_metre,
            c,
            rho,
        );
        let broken = state.breaks.as_mut().map(|b| b.broken(t)).unwrap_or(false);
        let target_id = ms.dwell_point.map(|i| i as u32);
        let truth = TrackerTruth {
            commanded: if self.cell.machine.is_jointed() {
                nominal_point
            } else {
                v3(&ms.q)
            },
            joints: ms.q.as_slice().to_vec(),
            displacement: d,
            tool_point,
            point: x,
            range: rho,
            warmup_range_error: warmup,
            refraction_range_error: refraction,
            true_index: 1.0 + n_true,
            range_sigma: sigma_eff,
        };
        let sample = if broken {
            TrackerSample {
                t,
                target_id,
                cycle: ms.cycle,
                point: Vector3::repeat(f64::NAN),
                range: f64::NAN,
                azimuth: f64::NAN,
                elevation: f64::NAN,
                covariance: Matrix3::repeat(f64::NAN),
                air_temperature: t_station,
                air_pressure: p_station,
                air_humidity: h_station,
                refractive_index: 1.0 + n_station,
                status: TrackerStatus::BeamBroken,
            }
        } else {
            let noise = &mut state.noise;
            let rho_m = prediction.measured_range()
                + if sigma_eff > 0.0 {
                    sigma_eff * noise.normal()
                } else {
                    0.0
                };
            let (az_m, el_m) = if spec.angular_noise > 0.0 {
                (
                    az + spec.angular_noise * noise.normal(),
                    el + spec.angular_noise * noise.normal(),
                )
            } else {
                (az, el)
            };
            let stated =
                stated_range_sigma(spec.range_noise_constant, spec.range_noise_per_metre, rho_m);
            TrackerSample {
                t,
                target_id,
                cycle: ms.cycle,
                point: from_spherical(rho_m, az_m, el_m),
                range: rho_m,
                azimuth: az_m,
                elevation: el_m,
                covariance: point_covariance(
                    rho_m,
                    az_m,
                    el_m,
                    stated,
                    spec.angular_noise,
                    spec.angular_noise,
                ),
                air_temperature: t_station,
                air_pressure: p_station,
                air_humidity: h_station,
                refractive_index: 1.0 + n_station,
                status: TrackerStatus::Ok,
            }
        };
        Ok((Sample::Tracker(sample), SampleTruth::Tracker(truth)))
    }

    fn probe_hit(&mut self, ev: DwellEvent) -> Result<(Sample, SampleTruth), PhysicsError> {
        let spec = self
            .cell
            .probe
            .as_ref()
            .expect("probe events exist only with a probe");
        let seg = &self.cell.program.segments[ev.segment];
        let point = seg.dwell_point.unwrap_or(0);
        let u = spec.directions[ev.sub];
        // The approach of each axis that moves while probing is the probing direction.
        let mut approach = seg.approach.clone();
        for k in 0..3 {
            if u[k] != 0.0 {
                approach[k] = u[k].signum();
            }
        }
        let ms = MotionState {
            q: seg.to.clone(),
            velocity: DVector::zeros(seg.to.len()),
            approach,
            dwell_point: Some(point),
            cycle: Some(ev.cycle),
        };
        self.set_signals(ev.t, &ms);
        // the surface point is the program point; the stylus is a point (radius 0), so the
        // reading is where the machine thinks the contact is
        let nominal = self.cell.machine.nominal_tool_point(&v3(&seg.to));
        let hit = ProbeTarget {
            surface: nominal,
            approach: u,
            stylus_radius: 0.0,
        };
        let prediction = self.model.probe_hit(
            None,
            &self.params,
            &self.kinematics,
            ms.q.as_slice(),
            &mut self.signals,
            &hit,
        )?;
        let (mut d, pretravel) = (prediction.machine, prediction.pretravel);
        let mut centre = prediction.centre;
        // the following error and the test-only disturbances displace the machine as a term
        // would: the axes read −δ
        let delta = self.beyond_the_terms(ev.t, &ms);
        d += delta;
        centre -= delta;
        let noise = Vector3::new(
            self.probe_noise.normal(),
            self.probe_noise.normal(),
            self.probe_noise.normal(),
        ) * spec.noise;
        let recorded = centre + noise;
        let s = ProbeHitSample {
            t: ev.t,
            target_id: point as u32,
            cycle: ev.cycle,
            direction_index: ev.sub as u32,
            direction: u,
            nominal,
            recorded,
            covariance: Matrix3::identity() * (spec.noise * spec.noise),
        };
        Ok((
            Sample::ProbeHit(s),
            SampleTruth::ProbeHit {
                displacement: d,
                pretravel,
            },
        ))
    }

    fn camera_request(&mut self, ev: DwellEvent) -> Result<(Sample, SampleTruth), PhysicsError> {
        let spec = self
            .cell
            .camera
            .as_ref()
            .expect("camera events exist only with a camera");
        let seg = &self.cell.program.segments[ev.segment];
        let ms = MotionState {
            q: seg.to.clone(),
            velocity: DVector::zeros(seg.to.len()),
            approach: seg.approach.clone(),
            dwell_point: seg.dwell_point,
            cycle: Some(ev.cycle),
        };
        let tool = self.tool_state(ev.t, &ms)?;
        // the camera is mounted on the tool: its pose is the tool pose followed by the mount
        let (nominal_camera, camera) = self.model.camera_pose(None, &tool)?;
        let plate = spec.plate.pose(&nominal_camera);
        let centre = plate.translation.vector;
        let plate_position = centre
            + self.model.workpiece_displacement(
                &self.params,
                &mut self.signals,
                centre,
                None,
                1.0,
            )?;
        let brown_conrady = matches!(spec.lens().distortion, Distortion::BrownConrady(_));
        let mut corners = Vec::with_capacity(4 * PLATE_MARKERS);
        for f in spec.plate.corners_in_workpiece(&nominal_camera) {
            corners.push(
                self.model
                    .camera(None, &self.params, &tool, &mut self.signals, &f)?
                    .pixel,
            );
        }
        let mut marker_points = Vec::with_capacity(PLATE_MARKERS);
        for k in 0..PLATE_MARKERS {
            let f = plate
                .transform_point(&spec.plate.marker_centre(k).into())
                .coords;
            marker_points.push(
                self.model
                    .camera(None, &self.params, &tool, &mut self.signals, &f)?
                    .measured_point,
            );
        }
        let s = CameraFrameRequest {
            t: ev.t,
            target_id: seg.dwell_point.unwrap_or(0) as u32,
            cycle: ev.cycle,
            position: camera.translation.vector,
            rotation: camera.rotation.to_rotation_matrix().into_inner(),
            nominal_position: nominal_camera.translation.vector,
            nominal_rotation: nominal_camera.rotation.to_rotation_matrix().into_inner(),
            plate_position,
            plate_rotation: plate.rotation.to_rotation_matrix().into_inner(),
            corners: brown_conrady.then_some(corners),
            marker_points,
        };
        let tool_point = tool.truth.translation.vector;
        Ok((
            Sample::CameraFrameRequest(s),
            SampleTruth::CameraFrameRequest {
                tool_point,
                joints: seg.to.as_slice().to_vec(),
                displacement: tool.d,
            },
        ))
    }
}

/// The first three joint values (x, y, z of a cartesian or delta program).
fn v3(q: &DVector<f64>) -> Vector3<f64> {
    Vector3::new(q[0], q[1], q[2])
}
