//! Lumped thermal model of a shift: produces temperature histories for named sensors, for the
//! simulator's true thermal terms. Deterministic given a seed.
//!
//! * Ambient: T_a(t) = mean + A·sin(2π t/P + φ) + drift·t + w(t), w a random walk with
//!   `walk_std` K/√s (zero → purely deterministic).
//! * Heat sources (motors, spindle) have a duty schedule: piecewise-constant levels in [0, 1].
//! * Each structure node relaxes to ambient plus its heating with a first-order time constant:
//!   τ·dT/dt = T_a(t) + Σ_s g_s·duty_s(t) − T,   g_s = steady-state rise at full duty (K).
//!   Integrated exactly over each step with inputs held (zero-order hold):
//!   T_{k+1} = T*_k + (T_k − T*_k)·e^(−Δt/τ),  T*_k = T_a(t_k) + Σ g_s·duty_s(t_k).
//! * Sensors read the ambient or a node, plus a bias and white noise (`noise_std`, K).
//!
//! Times are seconds from the start of the shift; temperatures °C.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::{BTreeMap, BTreeSet};
use std::f64::consts::TAU;

use crate::error::PhysicsError;
use crate::instrument::edlen::normal;
use crate::temperature_timeline::{TemperatureHistory, TemperatureTimeline};

/// Ambient temperature cycle.
#[derive(Debug, Clone, PartialEq)]
pub struct AmbientCycle {
    pub mean: f64,
    pub amplitude: f64,
    pub period: f64,
    pub phase: f64,
    /// Linear drift, K/s.
    pub drift: f64,
    /// Random-walk intensity, K/√s.
    pub walk_std: f64,
}

impl AmbientCycle {
    /// Deterministic part of the ambient at time t.
    pub fn deterministic(&self, t: f64) -> f64 {
        self.mean + self.amplitude * (TAU * t / self.period + self.phase).sin() + self.drift * t
    }
}

/// A piece of a duty schedule: `level` ∈ [0, 1] on [start, end) s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DutySegment {
    pub start: f64,
    pub end: f64,
    pub level: f64,
}

/// A heat source (motor, spindle) with its duty schedule (level 0 outside all segments).
#[derive(Debug, Clone, PartialEq)]
pub struct HeatSource {
    pub name: String,
    pub duty: Vec<DutySegment>,
}

impl HeatSource {
    pub fn level(&self, t: f64) -> f64 {
        self.duty
            .iter()
            .filter(|s| t >= s.start && t < s.end)
            .map(|s| s.level)
            .sum::<f64>()
            .min(1.0)
    }
}

/// A lumped structure node (column, head, table, ...).
#[derive(Debug, Clone, PartialEq)]
pub struct StructureNode {
    pub name: String,
    /// First-order time constant, s.
    pub time_constant: f64,
    /// (heat source name, steady-state rise at full duty in K).
    pub heating: Vec<(String, f64)>,
    /// Initial temperature, °C (None = ambient at t = 0).
    pub initial: Option<f64>,
}

/// Where a sensor sits.
#[derive(Debug, Clone, PartialEq)]
pub enum SensorLocation {
    Ambient,
    Node(String),
}

/// A temperature sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalSensor {
    pub name: String,
    pub location: SensorLocation,
    pub bias: f64,
    pub noise_std: f64,
}

/// The whole shift model.
#[derive(Debug, Clone, PartialEq)]
pub struct ShiftThermalModel {
    pub ambient: AmbientCycle,
    pub sources: Vec<HeatSource>,
    pub nodes: Vec<StructureNode>,
    pub sensors: Vec<ThermalSensor>,
}

/// Sampled temperatures of every sensor (and the true ambient and nodes, for reference).
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureLog {
    pub times: Vec<f64>,
    /// Sensor readings by sensor name.
    pub sensors: BTreeMap<String, Vec<f64>>,
    /// True (noise-free) node temperatures by node name, and `ambient`.
    pub truth: BTreeMap<String, Vec<f64>>,
}

impl TemperatureLog {
    /// One sensor as a [`TemperatureHistory`] (for `thermal_growth` with lag).
    pub fn history(&self, sensor: &str) -> Option<TemperatureHistory> {
        let v = self.sensors.get(sensor)?;
        Some(TemperatureHistory {
            samples: self.times.iter().copied().zip(v.iter().copied()).collect(),
        })
    }
    /// History truncated at time t (inclusive) — what a causal filter has seen at t.
    pub fn history_until(&self, sensor: &str, t: f64) -> Option<TemperatureHistory> {
        let mut h = self.history(sensor)?;
        h.samples.retain(|(ts, _)| *ts <= t);
        Some(h)
    }
    /// Every sensor's samples as a shared timeline (its clock: this log's times).
    pub fn timeline(&self) -> std::sync::Arc<TemperatureTimeline> {
        let timeline = TemperatureTimeline::new();
        for (name, values) in &self.sensors {
            timeline.add_sensor(name);
            for (&t, &v) in self.times.iter().zip(values) {
                // the log's times increase strictly and its values are finite (simulate's own)
                let _ = timeline.push(name, t, v);
            }
        }
        std::sync::Arc::new(timeline)
    }

    /// Put every sensor's reading at time t (interpolated), the time, and the timeline (its
    /// history up to t is what a lag reads) into `signals`, as the twin sees them at that instant.
    pub fn fill_signals(&self, t: f64, signals: &mut crate::signals::Signals) {
        for name in self.sensors.keys() {
            if let Some(v) = self.at(name, t) {
                signals.temperatures.insert(name.clone(), v);
            }
        }
        signals.time = Some(t);
        signals.timeline = Some(self.timeline());
    }

    /// Reading of a sensor at time t, linearly interpolated between samples.
    pub fn at(&self, sensor: &str, t: f64) -> Option<f64> {
        let v = self.sensors.get(sensor)?;
        let i = self.times.partition_point(|ts| *ts <= t);
        if i == 0 {
            return v.first().copied();
        }
        if i >= self.times.len() {
            return v.last().copied();
        }
        let (t0, t1) = (self.times[i - 1], self.times[i]);
        Some(v[i - 1] + (v[i] - v[i - 1]) * (t - t0) / (t1 - t0))
    }
}

fn invalid(what: &str, reason: String) -> PhysicsError {
    PhysicsError::InvalidInput {
        what: format!("shift thermal model: {what}"),
        reason,
    }
}

impl ShiftThermalModel {
    /// Check names, references, time constants and duty levels.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        if !(self.ambient.period > 0.0) {
            return Err(invalid(
                "ambient.period",
                format!("must be > 0 s, got {}", self.ambient.period),
            ));
        }
        if self.ambient.walk_std < 0.0 {
            return Err(invalid("ambient.walk_std", "must be ≥ 0".into()));
        }
        let sources: BTreeSet<&str> = self.sources.iter().map(|s| s.name.as_str()).collect();
        if sources.len() != self.sources.len() {
            return Err(invalid("sources", "duplicate heat source name".into()));
        }
        for s in &self.sources {
            for d in &s.duty {
                if !(d.level >= 0.0 && d.level <= 1.0 && d.end > d.start) {
                    return Err(invalid(
                        &format!("source `{}` duty", s.name),
                        format!(
                            "needs start < end and level in [0, 1], got [{}, {}) level {}",
                            d.start, d.end, d.level
                        ),
                    ));
                }
            }
        }
        let nodes: BTreeSet<&str> = self.nodes.iter().map(|n| n.name.as_str()).collect();
        if nodes.len() != self.nodes.len() || nodes.contains("ambient") {
            return Err(invalid(
                "nodes",
                "duplicate node name (or a node called `ambient`)".into(),
            ));
        }
        for n in &self.nodes {
            if !(n.time_constant > 0.0) {
                return Err(invalid(
                    &format!("node `{}`", n.name),
                    format!("time_constant must be > 0 s, got {}", n.time_constant),
                ));
            }
            for (src, _) in &n.heating {
                if !sources.contains(src.as_str()) {
                    return Err(invalid(
                        &format!("node `{}`", n.name),
                        format!("heating refers to unknown source `{src}`"),
                    ));
                }
            }
        }
        let mut names = BTreeSet::new();
        for s in &self.sensors {
            if !names.insert(s.name.as_str()) {
                return Err(invalid("sensors", format!("duplicate sensor `{}`", s.name)));
            }
            if let SensorLocation::Node(n) = &s.location {
                if !nodes.contains(n.as_str()) {
                    return Err(invalid(
                        &format!("sensor `{}`", s.name),
                        format!("refers to unknown node `{n}`"),
                    ));
                }
            }
            if s.noise_std < 0.0 {
                return Err(invalid(
                    &format!("sensor `{}`", s.name),
                    "noise_std must be ≥ 0".into(),
                ));
            }
        }
        Ok(())
    }

    /// Simulate from t = 0 to `duration` with step `dt` (s); deterministic in `seed`.
    pub fn simulate(
        &self,
        duration: f64,
        dt: f64,
        seed: u64,
    ) -> Result<TemperatureLog, PhysicsError> {
        self.validate()?;
        if !(dt > 0.0) || !(duration >= 0.0) || duration / dt > 1e7 {
            return Err(invalid("simulate", format!("needs dt > 0, duration ≥ 0 and at most 1e7 steps, got dt {dt}, duration {duration}")));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let steps = (duration / dt).round() as usize;
        let mut walk = 0.0;
        let mut amb = self.ambient.deterministic(0.0);
        let mut temps: Vec<f64> = self
            .nodes
            .iter()
            .map(|n| n.initial.unwrap_or(amb))
            .collect();
        let mut log = TemperatureLog {
            times: Vec::with_capacity(steps + 1),
            sensors: BTreeMap::new(),
            truth: BTreeMap::new(),
        };
        for k in 0..=steps {
            let t = k as f64 * dt;
            if k > 0 {
                // advance nodes over [t − dt, t) with inputs held at t − dt
                let tp = t - dt;
                for (n, temp) in self.nodes.iter().zip(temps.iter_mut()) {
                    let heat: f64 = n
                        .heating
                        .iter()
                        .map(|(src, g)| {
                            g * self
                                .sources
                                .iter()
                                .find(|s| &s.name == src)
                                .map(|s| s.level(tp))
                                .unwrap_or(0.0)
                        })
                        .sum();
                    let target = amb + heat;
                    *temp = target + (*temp - target) * (-dt / n.time_constant).exp();
                }
                walk += self.ambient.walk_std * dt.sqrt() * normal(&mut rng);
                amb = self.ambient.deterministic(t) + walk;
            }
            log.times.push(t);
            log.truth.entry("ambient".into()).or_default().push(amb);
            for (n, temp) in self.nodes.iter().zip(&temps) {
                log.truth.entry(n.name.clone()).or_default().push(*temp);
            }
            for s in &self.sensors {
                let truth = match &s.location {
                    SensorLocation::Ambient => amb,
                    SensorLocation::Node(n) => {
                        temps[self.nodes.iter().position(|x| &x.name == n).unwrap_or(0)]
                    }
                };
                let noise = if s.noise_std > 0.0 {
                    s.noise_std * normal(&mut rng)
                } else {
                    0.0
                };
                log.sensors
                    .entry(s.name.clone())
                    .or_default()
                    .push(truth + s.bias + noise);
            }
        }
        Ok(log)
    }

    /// An 8-hour shift of an XFYZ milling machine: workshop ambient (20 °C ± 1 K daily cycle,
    /// +0.1 K/h drift), axis motors and spindle running in work blocks with breaks; nodes for
    /// column (τ 1 h), spindle head (τ 20 min) and table (τ 2 h); sensors `ambient`, `column`,
    /// `head`, `table`, `x_left`, `x_right` (0.02 K noise).
    pub fn example_machine_shift() -> Self {
        let h = 3600.0;
        let work = |lvl: f64| {
            vec![
                DutySegment {
                    start: 0.5 * h,
                    end: 2.5 * h,
                    level: lvl,
                },
                DutySegment {
                    start: 2.75 * h,
                    end: 4.5 * h,
                    level: lvl,
                },
                DutySegment {
                    start: 5.0 * h,
                    end: 7.5 * h,
                    level: lvl,
                },
            ]
        };
        let node = |name: &str, tau: f64, heating: Vec<(&str, f64)>| StructureNode {
            name: name.into(),
            time_constant: tau,
            heating: heating
                .into_iter()
                .map(|(s, g)| (s.to_string(), g))
                .collect(),
            initial: None,
        };
        let sensor = |name: &str, loc: SensorLocation| ThermalSensor {
            name: name.into(),
            location: loc,
            bias: 0.0,
            noise_std: 0.02,
        };
        ShiftThermalModel {
            ambient: AmbientCycle {
                mean: 20.0,
                amplitude: 1.0,
                period: 24.0 * h,
                phase: -std::f64::consts::FRAC_PI_2,
                drift: 0.1 / h,
                walk_std: 0.002,
            },
            sources: vec![
                HeatSource {
                    name: "axis_motors".into(),
                    duty: work(0.6),
                },
                HeatSource {
                    name: "spindle".into(),
                    duty: work(0.8),
                },
            ],
            nodes: vec![
                node("column", h, vec![("axis_motors", 1.5), ("spindle", 1.0)]),
                node(
                    "head",
                    h / 3.0,
                    vec![("spindle", 4.0), ("axis_motors", 0.5)],
                ),
                node("table", 2.0 * h, vec![("axis_motors", 0.8)]),
            ],
            sensors: vec![
                sensor("ambient", SensorLocation::Ambient),
                sensor("column", SensorLocation::Node("column".into())),
                sensor("head", SensorLocation::Node("head".into())),
                sensor("table", SensorLocation::Node("table".into())),
                sensor("x_left", SensorLocation::Node("table".into())),
                sensor("x_right", SensorLocation::Ambient),
            ],
        }
    }
}
