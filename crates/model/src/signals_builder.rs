//! The signals builder: recorded time series → [`Signals`] at any instant, by interpolation.
//! Pure (no bag or DDS I/O): the caller pushes samples from whatever carried them (a bag, a
//! live subscription, an import) and asks for the signals at the time of a measurement.
//!
//! What it reads, and how each signal is formed (times: integer ns on the recording's clock;
//! `Signals::time` is that clock in seconds):
//! * **commanded joints** (positions, and velocities when recorded), in the machine's joint
//!   order ([`MachineGeometry::joint_names`]); the axis signals are the first three joints of a
//!   cartesian, delta or five-axis machine (none on an arm), and a five-axis table's `b` and `c`
//!   its rotary positions, as [`crate::ForwardModel::set_motion`] sets them. Positions: the sample at a sample's time, else the linear interpolation between
//!   two samples at most `max_joint_gap` apart. Velocity: the recorded one when the message
//!   carries it (interpolated between samples); else from the trajectory — the slope of the
//!   interval that starts at the instant (at the newest sample: the one that ends there).
//!   Approach direction: the sign of the last non-zero motion ([`crate::approach_rule`]:
//!   recorded velocity first, then positions with a deadband); between two samples, the sign of
//!   the motion over that interval when the axis moves. An explicitly recorded approach
//!   ([`SignalsBuilder::push_approach`], e.g. an import's `approach.<axis>` column) takes
//!   precedence for its axis.
//! * **temperatures** per sensor: interpolated between samples at most `max_slow_gap` apart
//!   (nothing after a sensor's last sample), and every sample goes into the shared
//!   [`TemperatureTimeline`] that lagged terms read up to the instant.
//! * **station air** (T °C, p Pa, RH %): sampled streams like temperatures.
//! * **power-on instant** of the instrument and the **load**: states — the latest received at
//!   or before the instant (or the first one, for a latched state received after it). Time
//!   since power-on is None before the power-on instant.
//!
//! Missing values stay `None`: never extrapolated, never invented.
//!
//! Streaming: samples are pushed in time order per stream; [`SignalsBuilder::ready`] says when
//! every stream has moved past an instant (or can no longer bracket it), so an online user
//! holds a measurement until then and gets the same signals an offline pass over the whole
//! recording gives. With `joint_window` the high-rate joint stream keeps only that much
//! history (bounded memory for a shift); the approach state survives the window.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

use metrocell_physics::{Signals, TemperatureTimeline};
use nalgebra::Vector3;

use crate::approach_rule::{motion_sign, ApproachTracker};
use crate::machine::{MachineGeometry, MachineKinematics};
use crate::sampled_series::{SampledSeries, StateSeries};

/// Nanoseconds per second.
const NS: f64 = 1e9;

/// How the builder interpolates and when it gives up.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalsBuilderOptions {
    /// Position change that counts as motion for the approach rule (m for linear joints, rad
    /// for rotary ones); see [`crate::approach_rule`] for why 1e-9.
    pub approach_deadband: f64,
    /// Recorded velocity below which a joint counts as at rest (m/s or rad/s).
    pub velocity_deadband: f64,
    /// Approach direction before a joint's first recorded motion: None = unknown (the
    /// default), Some(+1.0) for a machine homed from the negative side (the twin's convention).
    pub initial_approach: Option<f64>,
    /// Longest interval (s) between two joint samples that is interpolated (a longer one is a
    /// gap in the recording: no positions inside it).
    pub max_joint_gap: f64,
    /// Same for temperatures and air (s); also how long [`SignalsBuilder::ready`] waits for a
    /// sample after an instant before giving up on bracketing it.
    pub max_slow_gap: f64,
    /// Streaming: joint samples older than the newest by more than this (s) are dropped;
    /// None keeps all.
    pub joint_window: Option<f64>,
    /// Streaming: temperature samples older than the newest by more than this (s) leave the
    /// series that instantaneous temperatures are interpolated from; None keeps all.
    pub temperature_window: Option<f64>,
    /// Streaming: seconds of each sensor's history the lag timeline keeps at full rate; older
    /// history is coarsened to one sample a minute
    /// ([`TemperatureTimeline::with_full_rate`]); None keeps every sample.
    pub temperature_full_rate: Option<f64>,
}

impl Default for SignalsBuilderOptions {
    fn default() -> Self {
        Self {
            approach_deadband: 1e-9,
            velocity_deadband: 1e-9,
            initial_approach: None,
            max_joint_gap: 1.0,
            max_slow_gap: 600.0,
            joint_window: None,
            temperature_window: None,
            temperature_full_rate: None,
        }
    }
}

fn ns(seconds: f64) -> i64 {
    (seconds * NS).round() as i64
}

/// The commanded joint stream: flat storage, `n` values per sample.
#[derive(Debug, Clone)]
struct JointStream {
    n: usize,
    times: VecDeque<i64>,
    positions: VecDeque<f64>,
    /// NaN where the message carried no velocity.
    velocities: VecDeque<f64>,
    /// Approach after each sample: +1, −1, 0 = unknown.
    approach: VecDeque<i8>,
    trackers: Vec<ApproachTracker>,
}

impl JointStream {
    fn get(&self, store: &VecDeque<f64>, k: usize, j: usize) -> f64 {
        store[k * self.n + j]
    }
    fn forget_before(&mut self, t_ns: i64) {
        // keep the last sample before t_ns: it brackets t_ns
        let k = self
            .times
            .partition_point(|&ts| ts < t_ns)
            .saturating_sub(1);
        if k > 0 {
            self.times.drain(..k);
            self.positions.drain(..k * self.n);
            self.velocities.drain(..k * self.n);
            self.approach.drain(..k * self.n);
        }
    }
}

/// The joints' motion at one instant (all joints, the machine's order).
#[derive(Debug, Clone, PartialEq)]
pub struct JointMotion {
    pub positions: Vec<f64>,
    pub velocities: Vec<Option<f64>>,
    pub approach: Vec<Option<f64>>,
}

/// Builds [`Signals`] from recorded streams; see the module docs.
#[derive(Debug, Clone)]
pub struct SignalsBuilder {
    options: SignalsBuilderOptions,
    joint_names: Vec<String>,
    /// The first three joints are the linear axes (not on an arm).
    has_axes: bool,
    /// The joints that are the rotary axes A, B, C (a five-axis table's `b` and `c`).
    rotary: [Option<usize>; 3],
    joints: JointStream,
    temperatures: BTreeMap<String, SampledSeries>,
    timeline: Arc<TemperatureTimeline>,
    /// Air temperature °C, pressure Pa, humidity %RH.
    air: [SampledSeries; 3],
    air_expected: [bool; 3],
    power_on: StateSeries<i64>,
    load: StateSeries<Vector3<f64>>,
    /// The recorded active tool offset (m, machine frame), and the model's, which a reading's
    /// [`Signals::tool_offset_shift`] is measured from.
    tool_offset: StateSeries<Vector3<f64>>,
    model_tool_offset: Vector3<f64>,
    /// Each accelerometer's latest reading (specific force, its own frame, m/s²).
    accelerations: BTreeMap<String, StateSeries<Vector3<f64>>>,
    explicit_approach: [StateSeries<f64>; 3],
    /// The newest time the recording has reached (any stream, or [`Self::observe_time`]).
    newest_ns: Option<i64>,
    /// The caller will push commanded joints ([`Self::expect_joints`]).
    joints_expected: bool,
}

impl SignalsBuilder {
    /// A builder for a machine: its joint names, whether it has linear axes, and which joints
    /// are rotary axes (the axis signals as [`crate::ForwardModel::set_motion`] sets them).
    pub fn for_machine(machine: &MachineGeometry, options: SignalsBuilderOptions) -> Self {
        let mut b = Self::new(
            machine.joint_names(),
            !matches!(machine.kinematics, MachineKinematics::SerialArm(_)),
            options,
        );
        if matches!(machine.kinematics, MachineKinematics::FiveAxis(_)) {
            b.rotary = [None, Some(3), Some(4)];
        }
        b.model_tool_offset = machine.tool_offset;
        b
    }

    /// A builder for joints named `joint_names` (in the model's order); with `has_axes` the first
    /// three are the linear axes x, y, z.
    pub fn new(joint_names: Vec<String>, has_axes: bool, options: SignalsBuilderOptions) -> Self {
        let n = joint_names.len();
        let timeline = match options.temperature_full_rate {
            Some(span) => TemperatureTimeline::with_full_rate(span),
            None => TemperatureTimeline::new(),
        };
        Self {
            joints: JointStream {
                n,
                times: VecDeque::new(),
                positions: VecDeque::new(),
                velocities: VecDeque::new(),
                approach: VecDeque::new(),
                trackers: vec![ApproachTracker::new(options.initial_approach); n],
            },
            has_axes: has_axes && n >= 3,
            rotary: [None; 3],
            joint_names,
            options,
            temperatures: BTreeMap::new(),
            timeline: Arc::new(timeline),
            air: Default::default(),
            air_expected: [false; 3],
            power_on: StateSeries::default(),
            load: StateSeries::default(),
            tool_offset: StateSeries::default(),
            model_tool_offset: Vector3::zeros(),
            accelerations: BTreeMap::new(),
            explicit_approach: Default::default(),
            newest_ns: None,
            joints_expected: false,
        }
    }

    /// Declare that commanded joints will be pushed: [`Self::ready`] then waits for them even
    /// before their first sample.
    pub fn expect_joints(&mut self) {
        self.joints_expected = true;
    }

    /// Declare a temperature sensor that will be pushed (its topic exists): [`Self::ready`] waits
    /// for it as for one that has samples.
    pub fn expect_temperature(&mut self, sensor: &str) {
        self.temperatures.entry(sensor.to_string()).or_default();
        self.timeline.add_sensor(sensor);
    }

    pub fn options(&self) -> &SignalsBuilderOptions {
        &self.options
    }

    pub fn joint_names(&self) -> &[String] {
        &self.joint_names
    }

    /// The shared temperature timeline (every instant's signals point to it).
    pub fn timeline(&self) -> &Arc<TemperatureTimeline> {
        &self.timeline
    }

    /// The recording has reached `t_ns` (e.g. a message of any topic was logged then): lets
    /// [`Self::ready`] conclude that a slow stream will not bracket an earlier instant.
    pub fn observe_time(&mut self, t_ns: i64) {
        self.newest_ns = Some(self.newest_ns.map_or(t_ns, |n| n.max(t_ns)));
    }

    /// A commanded joint state: `names` with `positions` (same length) and `velocities`
    /// (same length, or empty when not recorded; NaN entries count as not recorded). Refused
    /// (with the reason) when a machine joint is missing, a position is not finite, or the
    /// time does not come after the previous joint sample.
    pub fn push_joints(
        &mut self,
        t_ns: i64,
        names: &[String],
        positions: &[f64],
        velocities: &[f64],
    ) -> Result<(), String> {
        if positions.len() != names.len() {
            return Err(format!(
                "{} names but {} positions",
                names.len(),
                positions.len()
            ));
        }
        let with_velocity = velocities.len() == names.len();
        if let Some(&last) = self.joints.times.back() {
            if t_ns <= last {
                return Err(format!(
                    "joint state at {t_ns} ns does not come after the previous one at {last} ns"
                ));
            }
        }
        let mut q = Vec::with_capacity(self.joints.n);
        let mut v = Vec::with_capacity(self.joints.n);
        for name in &self.joint_names {
            let i = names
                .iter()
                .position(|x| x == name)
                .ok_or_else(|| format!("has no joint `{name}` (it names {})", names.join(", ")))?;
            if !positions[i].is_finite() {
                return Err(format!(
                    "joint `{name}` position {} is not finite",
                    positions[i]
                ));
            }
            q.push(positions[i]);
            v.push(if with_velocity {
                velocities[i]
            } else {
                f64::NAN
            });
        }
        let (db, vdb) = (
            self.options.approach_deadband,
            self.options.velocity_deadband,
        );
        for (j, tracker) in self.joints.trackers.iter_mut().enumerate() {
            tracker.update(q[j], Some(v[j]), db, vdb);
            self.joints
                .approach
                .push_back(tracker.direction().map_or(0, |d| d as i8));
        }
        self.joints.times.push_back(t_ns);
        self.joints.positions.extend(q);
        self.joints.velocities.extend(v);
        if let Some(w) = self.options.joint_window {
            self.joints.forget_before(t_ns - ns(w));
        }
        self.observe_time(t_ns);
        Ok(())
    }

    /// A reading of temperature sensor `sensor` (°C).
    pub fn push_temperature(
        &mut self,
        t_ns: i64,
        sensor: &str,
        celsius: f64,
    ) -> Result<(), String> {
        // the timeline first: it refuses whatever the series would (its seconds are a monotone
        // image of the nanoseconds), and a refused sample then changes neither
        self.timeline.push(sensor, t_ns as f64 / NS, celsius)?;
        let series = self.temperatures.entry(sensor.to_string()).or_default();
        series.push(t_ns, celsius)?;
        if let Some(w) = self.options.temperature_window {
            series.forget_before(t_ns - ns(w));
        }
        self.observe_time(t_ns);
        Ok(())
    }

    /// Declare an air stream that will be pushed (0 temperature, 1 pressure, 2 humidity).
    pub fn expect_air(&mut self, i: usize) {
        if let Some(e) = self.air_expected.get_mut(i) {
            *e = true;
        }
    }

    /// Station air temperature (°C).
    pub fn push_air_temperature(&mut self, t_ns: i64, celsius: f64) -> Result<(), String> {
        self.push_air(0, t_ns, celsius)
    }
    /// Station air pressure (Pa).
    pub fn push_air_pressure(&mut self, t_ns: i64, pascal: f64) -> Result<(), String> {
        self.push_air(1, t_ns, pascal)
    }
    /// Station relative humidity (%RH, 0..100).
    pub fn push_air_humidity(&mut self, t_ns: i64, percent: f64) -> Result<(), String> {
        self.push_air(2, t_ns, percent)
    }
    fn push_air(&mut self, i: usize, t_ns: i64, v: f64) -> Result<(), String> {
        self.air[i].push(t_ns, v)?;
        self.observe_time(t_ns);
        Ok(())
    }

    /// The instrument was powered on at `powered_on_ns` (message received at `t_ns`).
    pub fn push_power_on(&mut self, t_ns: i64, powered_on_ns: i64) {
        self.power_on.push(t_ns, powered_on_ns);
        self.observe_time(t_ns);
    }

    /// The load force (N, machine frame) from `t_ns` on.
    pub fn push_load(&mut self, t_ns: i64, force: Vector3<f64>) -> Result<(), String> {
        if !force.iter().all(|v| v.is_finite()) {
            return Err(format!("load force {force:?} is not finite"));
        }
        self.load.push(t_ns, force);
        self.observe_time(t_ns);
        Ok(())
    }

    /// The active tool's (target's) offset from the spindle's gauge point (m, machine frame)
    /// from `t_ns` on: readings then carry its difference from the model's tool offset.
    pub fn push_tool_offset(&mut self, t_ns: i64, offset: Vector3<f64>) -> Result<(), String> {
        if !offset.iter().all(|v| v.is_finite()) {
            return Err(format!("tool offset {offset:?} m is not finite"));
        }
        if offset.norm() > 5.0 {
            return Err(format!(
                "tool offset ({:.3}, {:.3}, {:.3}) m is longer than 5 m: is it in mm? (SI on the wire: metres)",
                offset.x, offset.y, offset.z
            ));
        }
        self.tool_offset.push(t_ns, offset);
        self.observe_time(t_ns);
        Ok(())
    }

    /// An accelerometer's reading (specific force in its own frame, m/s²) from `t_ns` on.
    pub fn push_acceleration(
        &mut self,
        t_ns: i64,
        sensor: &str,
        specific_force: Vector3<f64>,
    ) -> Result<(), String> {
        if !specific_force.iter().all(|v| v.is_finite()) {
            return Err(format!(
                "accelerometer `{sensor}` reading {specific_force:?} is not finite"
            ));
        }
        self.accelerations
            .entry(sensor.to_string())
            .or_default()
            .push(t_ns, specific_force);
        self.observe_time(t_ns);
        Ok(())
    }

    /// A recorded approach direction of linear axis `axis` (0 = x, 1 = y, 2 = z): +1 or −1 from
    /// `t_ns` on. It replaces the rule for that axis.
    pub fn push_approach(&mut self, t_ns: i64, axis: usize, direction: f64) -> Result<(), String> {
        if axis > 2 || !(direction == 1.0 || direction == -1.0) {
            return Err(format!(
                "approach of axis {axis} must be +1 or -1 for axis 0..=2, got {direction}"
            ));
        }
        self.explicit_approach[axis].push(t_ns, direction);
        self.observe_time(t_ns);
        Ok(())
    }

    /// Whether `t_ns` can be answered for good: the recording has moved past it (so every
    /// message stamped at it has been pushed), the joint stream has reached it, and every
    /// temperature and air stream has reached it or can no longer bracket it (the recording is
    /// more than `max_slow_gap` past it). Streams count once they have a sample or were
    /// declared ([`Self::expect_joints`], [`Self::expect_temperature`], [`Self::expect_air`]).
    /// An online user holds a measurement until then; at the end of a recording, everything
    /// still held is answered as it stands.
    pub fn ready(&self, t_ns: i64) -> bool {
        let newest = self.newest_ns.unwrap_or(i64::MIN);
        if newest <= t_ns {
            return false;
        }
        let joints = match self.joints.times.back() {
            Some(&t) => t >= t_ns,
            None => !self.joints_expected,
        };
        let slow_gap = ns(self.options.max_slow_gap);
        let slow = self
            .temperatures
            .values()
            .chain(
                self.air
                    .iter()
                    .zip(self.air_expected)
                    .filter(|(s, expected)| *expected || !s.is_empty())
                    .map(|(s, _)| s),
            )
            .all(|s| {
                s.newest().is_some_and(|t| t >= t_ns) || newest.saturating_sub(slow_gap) >= t_ns
            });
        joints && slow
    }

    /// The joints' motion at `t_ns`, or None when no joint sample is at or around it.
    pub fn joints_at(&self, t_ns: i64) -> Option<JointMotion> {
        let js = &self.joints;
        let n = js.n;
        let k = js.times.partition_point(|&ts| ts <= t_ns);
        if k == 0 {
            return None;
        }
        let gap = ns(self.options.max_joint_gap);
        let db = self.options.approach_deadband;
        let t0 = js.times[k - 1];
        let slope = |a: usize, b: usize, j: usize| {
            (js.get(&js.positions, b, j) - js.get(&js.positions, a, j))
                / ((js.times[b] - js.times[a]) as f64 / NS)
        };
        let within = |a: usize, b: usize| b < js.times.len() && js.times[b] - js.times[a] <= gap;
        let mut m = JointMotion {
            positions: Vec::with_capacity(n),
            velocities: Vec::with_capacity(n),
            approach: Vec::with_capacity(n),
        };
        if t0 == t_ns {
            let k = k - 1;
            for j in 0..n {
                m.positions.push(js.get(&js.positions, k, j));
                let recorded = js.get(&js.velocities, k, j);
                m.velocities.push(if recorded.is_finite() {
                    Some(recorded)
                } else if within(k, k + 1) {
                    Some(slope(k, k + 1, j))
                } else if k > 0 && within(k - 1, k) {
                    Some(slope(k - 1, k, j))
                } else {
                    None
                });
                m.approach.push(direction(js.approach[k * n + j]));
            }
            return Some(m);
        }
        let (a, b) = (k - 1, k);
        if !within(a, b) {
            return None;
        }
        let f = (t_ns - t0) as f64 / (js.times[b] - t0) as f64;
        for j in 0..n {
            let (qa, qb) = (js.get(&js.positions, a, j), js.get(&js.positions, b, j));
            m.positions.push(qa + (qb - qa) * f);
            let (va, vb) = (js.get(&js.velocities, a, j), js.get(&js.velocities, b, j));
            m.velocities.push(Some(if va.is_finite() && vb.is_finite() {
                va + (vb - va) * f
            } else {
                slope(a, b, j)
            }));
            m.approach
                .push(motion_sign(qa, qb, db).or(direction(js.approach[a * n + j])));
        }
        Some(m)
    }

    /// The signals at `t_ns`: time, axis positions, velocities and approach directions,
    /// temperatures and the timeline, station air, time since power-on, load. `point`,
    /// `tracker_range` and the like are the model's to set. Every value the recording cannot
    /// give at that instant is None.
    pub fn signals_at(&self, t_ns: i64) -> Signals {
        let mut s = Signals {
            time: Some(t_ns as f64 / NS),
            timeline: Some(self.timeline.clone()),
            ..Signals::default()
        };
        if let Some(m) = self.joints_at(t_ns) {
            for (a, joint) in self.rotary.iter().enumerate() {
                s.rotary_position[a] = joint.and_then(|j| m.positions.get(j).copied());
            }
            if self.has_axes {
                for a in 0..3 {
                    s.axis_position[a] = Some(m.positions[a]);
                    s.axis_velocity[a] = m.velocities[a];
                    s.approach_direction[a] = m.approach[a];
                }
            }
        }
        if self.has_axes {
            for a in 0..3 {
                if !self.explicit_approach[a].is_empty() {
                    s.approach_direction[a] = self.explicit_approach[a].at(t_ns);
                }
            }
        }
        let slow_gap = ns(self.options.max_slow_gap);
        for (name, series) in &self.temperatures {
            if let Some(v) = series.at(t_ns, slow_gap) {
                s.temperatures.insert(name.clone(), v);
            }
        }
        s.air_temperature = self.air[0].at(t_ns, slow_gap);
        s.air_pressure = self.air[1].at(t_ns, slow_gap);
        s.air_humidity = self.air[2].at(t_ns, slow_gap);
        s.time_since_power_on = self
            .power_on
            .at(t_ns)
            .filter(|&on| on <= t_ns)
            .map(|on| (t_ns - on) as f64 / NS);
        s.load_force = self.load.at(t_ns);
        s.tool_offset_shift = self
            .tool_offset
            .at(t_ns)
            .map(|t| t - self.model_tool_offset);
        for (name, series) in &self.accelerations {
            if let Some(a) = series.at(t_ns) {
                s.accelerations.insert(name.clone(), a);
            }
        }
        s
    }

    /// Whether any sample of a stream has been pushed: joints, a temperature sensor, air
    /// (0 T, 1 p, 2 RH), power-on, load.
    pub fn has_joints(&self) -> bool {
        !self.joints.times.is_empty()
    }
    pub fn has_temperature(&self, sensor: &str) -> bool {
        self.temperatures.get(sensor).is_some_and(|s| !s.is_empty())
    }
    pub fn has_air(&self, i: usize) -> bool {
        self.air.get(i).is_some_and(|s| !s.is_empty())
    }
    pub fn has_power_on(&self) -> bool {
        !self.power_on.is_empty()
    }
    pub fn has_load(&self) -> bool {
        !self.load.is_empty()
    }
    /// The recorded active tool offset at `t_ns` (m, machine frame), None when none is recorded.
    pub fn tool_offset_at(&self, t_ns: i64) -> Option<Vector3<f64>> {
        self.tool_offset.at(t_ns)
    }
    pub fn has_tool_offset(&self) -> bool {
        !self.tool_offset.is_empty()
    }
    pub fn has_explicit_approach(&self, axis: usize) -> bool {
        self.explicit_approach
            .get(axis)
            .is_some_and(|s| !s.is_empty())
    }
    /// Joint samples held now (bounded by `joint_window`).
    pub fn joint_samples_held(&self) -> usize {
        self.joints.times.len()
    }
}

fn direction(d: i8) -> Option<f64> {
    (d != 0).then_some(d as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        ["x", "y", "z"].iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn positions_velocity_and_approach_of_a_recorded_trajectory() {
        let mut b = SignalsBuilder::new(names(), true, SignalsBuilderOptions::default());
        // x moves +0.1 m over 2 s (samples every 0.5 s), dwells, then moves back; no velocities
        let xs = [0.0, 0.0, 0.025, 0.05, 0.075, 0.1, 0.1, 0.1, 0.075];
        for (k, x) in xs.iter().enumerate() {
            b.push_joints(k as i64 * 500_000_000, &names(), &[*x, 0.2, 0.3], &[])
                .unwrap();
        }
        let s = b.signals_at(1_250_000_000);
        assert!(
            (s.axis_position[0].unwrap() - 0.0375).abs() < 1e-15,
            "{:?}",
            s.axis_position
        );
        assert_eq!(&s.axis_position[1..], [Some(0.2), Some(0.3)]);
        assert_eq!(s.axis_velocity[0], Some(0.05));
        assert_eq!(s.approach_direction[0], Some(1.0));
        assert_eq!(
            s.approach_direction[1], None,
            "y never moved and no initial direction is set"
        );
        assert_eq!(s.time, Some(1.25));
        // at a sample's time the interval starting there gives the velocity: 0.5 s is the
        // first sample of the move (still at 0) and already moving
        let s = b.signals_at(500_000_000);
        assert_eq!(
            (s.axis_position[0], s.axis_velocity[0]),
            (Some(0.0), Some(0.05))
        );
        // the dwell keeps +1; the way back turns it −1 (between the samples and at the last)
        assert_eq!(b.signals_at(3_250_000_000).approach_direction[0], Some(1.0));
        assert_eq!(
            b.signals_at(3_750_000_000).approach_direction[0],
            Some(-1.0)
        );
        assert_eq!(
            b.signals_at(4_000_000_000).approach_direction[0],
            Some(-1.0)
        );
        let v = b.signals_at(4_000_000_000).axis_velocity[0].unwrap();
        assert!(
            (v + 0.05).abs() < 1e-15,
            "the newest sample: the interval ending there, {v}"
        );
        assert_eq!(
            b.signals_at(4_000_000_001).axis_position[0],
            None,
            "never extrapolated"
        );
        assert!(b
            .push_joints(4_000_000_000, &names(), &[0.0; 3], &[])
            .is_err());
        assert!(b
            .push_joints(5_000_000_000, &names()[..2], &[0.0; 2], &[])
            .unwrap_err()
            .contains("no joint `z`"));
    }

    #[test]
    fn recorded_velocity_and_explicit_approach_take_precedence() {
        let mut b = SignalsBuilder::new(
            names(),
            true,
            SignalsBuilderOptions {
                initial_approach: Some(1.0),
                ..Default::default()
            },
        );
        b.push_joints(0, &names(), &[0.5, 0.0, 0.0], &[0.0, 0.0, 0.0])
            .unwrap();
        b.push_joints(10_000_000, &names(), &[0.5, 0.0, 0.0], &[-0.04, 0.0, 0.0])
            .unwrap();
        b.push_joints(
            20_000_000,
            &names(),
            &[0.4996, 0.0, 0.0],
            &[-0.04, 0.0, 0.0],
        )
        .unwrap();
        let s = b.signals_at(10_000_000);
        assert_eq!(
            s.approach_direction,
            [Some(-1.0), Some(1.0), Some(1.0)],
            "the move starts here: its velocity says so"
        );
        assert_eq!(s.axis_velocity[0], Some(-0.04));
        assert_eq!(b.signals_at(0).approach_direction[0], Some(1.0));
        b.push_approach(0, 1, -1.0).unwrap();
        assert_eq!(b.signals_at(10_000_000).approach_direction[1], Some(-1.0));
        assert!(b.push_approach(0, 1, 0.5).is_err());
    }

    #[test]
    fn temperatures_air_power_on_and_load() {
        let mut b = SignalsBuilder::new(names(), true, SignalsBuilderOptions::default());
        b.push_temperature(0, "column", 20.0).unwrap();
        b.push_temperature(10_000_000_000, "column", 21.0).unwrap();
        b.push_air_pressure(0, 101_300.0).unwrap();
        b.push_air_pressure(5_000_000_000, 101_300.0).unwrap();
        b.push_power_on(0, -1_200_000_000_000);
        b.push_load(5_000_000_000, Vector3::new(0.0, 0.0, -50.0))
            .unwrap();
        let s = b.signals_at(2_500_000_000);
        assert_eq!(s.temperatures["column"], 20.25);
        assert_eq!(s.air_pressure, Some(101_300.0));
        assert_eq!(s.air_temperature, None);
        assert_eq!(s.time_since_power_on, Some(1_202.5));
        assert_eq!(
            s.load_force,
            Some(Vector3::new(0.0, 0.0, -50.0)),
            "a latched state received later held before"
        );
        // the lag reads the timeline up to the instant: only the first sample by 2.5 s
        assert_eq!(
            s.lagged_temperature("thermal_growth[column]", "column", 600.0)
                .unwrap(),
            (20.0, 0.0)
        );
        assert_eq!(
            b.signals_at(10_000_000_001).temperatures.get("column"),
            None,
            "not past the last sample"
        );
        assert!(b.signals_at(-1).time_since_power_on.is_some());
        let mut later = SignalsBuilder::new(names(), true, SignalsBuilderOptions::default());
        later.push_power_on(0, 5_000_000_000);
        assert_eq!(
            later.signals_at(1_000_000_000).time_since_power_on,
            None,
            "not yet on"
        );
    }

    #[test]
    fn ready_waits_for_declared_streams_even_before_their_first_sample() {
        let mut b = SignalsBuilder::new(
            names(),
            true,
            SignalsBuilderOptions {
                max_slow_gap: 5.0,
                ..Default::default()
            },
        );
        b.expect_joints();
        b.expect_temperature("column");
        b.expect_air(1);
        b.observe_time(2_000_000_000);
        assert!(!b.ready(1_000_000_000), "no joint sample yet");
        b.push_joints(1_000_000_000, &names(), &[0.0; 3], &[])
            .unwrap();
        assert!(
            !b.ready(1_000_000_000),
            "the declared slow streams could still bracket it"
        );
        b.push_temperature(1_000_000_000, "column", 20.0).unwrap();
        b.push_air_pressure(1_500_000_000, 101_300.0).unwrap();
        assert!(b.ready(1_000_000_000));
        assert_eq!(b.signals_at(1_000_000_000).temperatures["column"], 20.0);
    }

    #[test]
    fn ready_waits_for_bracketing_samples_and_the_window_bounds_memory() {
        let opts = SignalsBuilderOptions {
            joint_window: Some(1.0),
            max_slow_gap: 5.0,
            ..Default::default()
        };
        let mut b = SignalsBuilder::new(names(), true, opts);
        b.push_temperature(0, "column", 20.0).unwrap();
        for k in 0..1000 {
            b.push_joints(k * 10_000_000, &names(), &[k as f64 * 1e-4, 0.0, 0.0], &[])
                .unwrap();
        }
        assert!(
            b.joint_samples_held() <= 102,
            "{} joint samples held",
            b.joint_samples_held()
        );
        let t = 9_000_000_000;
        assert!(
            !b.ready(t),
            "the temperature stream could still bracket 9 s"
        );
        assert!(
            !b.ready(9_990_000_000),
            "nothing after the newest sample yet"
        );
        b.observe_time(14_000_000_001);
        assert!(b.ready(t));
        assert!(b.signals_at(t).axis_position[0].is_some());
        assert_eq!(
            b.signals_at(5_000_000_000).axis_position[0],
            None,
            "older than the window"
        );
    }
}
