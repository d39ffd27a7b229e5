//! The signals a term reads: what the twin knows about the machine and its surroundings at the
//! instant a prediction is made. Every value is SI except temperatures, which are °C (as
//! `sensor_msgs/Temperature`), and relative humidity, which is in % (as the thesis' Edlén formula).

use nalgebra::{Vector2, Vector3};
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use crate::error::PhysicsError;
use crate::temperature_timeline::{LagUnavailable, TemperatureTimeline};

/// A linear machine axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];
    /// 0, 1, 2 for X, Y, Z.
    pub fn index(self) -> usize {
        self as usize
    }
    /// Unit vector of the axis in the machine frame. (Each a constant: the geometric terms
    /// build these for every reading, and a vector written element by element on the stack and
    /// read back whole stalled the model's inner loop.)
    #[inline]
    pub fn unit(self) -> Vector3<f64> {
        match self {
            Axis::X => Vector3::x(),
            Axis::Y => Vector3::y(),
            Axis::Z => Vector3::z(),
        }
    }
    pub fn name(self) -> &'static str {
        ["x", "y", "z"][self.index()]
    }
    pub fn parse(s: &str) -> Option<Axis> {
        match s.trim().to_ascii_lowercase().as_str() {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "z" => Some(Axis::Z),
            _ => None,
        }
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A rotary machine axis (ISO 841: A, B, C turn about x, y, z).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RotaryAxis {
    A,
    B,
    C,
}

impl RotaryAxis {
    /// 0, 1, 2 for A, B, C.
    pub fn index(self) -> usize {
        self as usize
    }
    pub fn name(self) -> &'static str {
        ["a", "b", "c"][self.index()]
    }
}

/// Kind of signal a term needs (the declaration; values live in [`Signals`]).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SignalKind {
    /// Commanded position of a linear axis, m.
    AxisPosition(Axis),
    /// Direction of approach of an axis: +1 moving positive, −1 moving negative.
    ApproachDirection(Axis),
    /// Velocity of an axis, m/s.
    AxisVelocity(Axis),
    /// Latest reading of a named temperature sensor, °C.
    Temperature(String),
    /// Time history of a named temperature sensor (for first-order lags), s and °C: the
    /// sensor's samples in [`Signals::timeline`] up to [`Signals::time`].
    TemperatureHistory(String),
    /// Air temperature at the weather station, °C.
    AirTemperature,
    /// Air pressure at the weather station, Pa.
    AirPressure,
    /// Relative humidity at the weather station, %.
    AirHumidity,
    /// Time since the instrument was powered on, s.
    TimeSincePowerOn,
    /// Load force acting on the structure (e.g. m·g of a payload), N, machine frame.
    LoadForce,
    /// Range (distance) measured by a tracker, m.
    TrackerRange,
    /// Point in normalised image coordinates (x/z, y/z) of the camera.
    ImagePoint,
    /// The nominal tool point in the frame machine-frame terms act in (the machine frame: q +
    /// tool offset on cartesian and delta machines, the tool tip in the machine frame on a
    /// five-axis machine, the nominal tool point on an arm), m.
    MachinePoint,
    /// Nominal position of a feature on the workpiece (the part, fixture or artefact), in the
    /// workpiece frame, m: what workpiece-frame terms displace.
    WorkpiecePoint,
    /// The true point an instrument sights (a tracker's reflector), in the frame instrument poses
    /// are given in (workpiece; an arm's cell frame), m: what `tracker_pose` maps into the
    /// instrument frame.
    TargetPoint,
    /// A point in the camera frame (x right, y down, z along the optical axis), m.
    CameraPoint,
    /// Unit vector of the probing (approach) direction in the probe frame.
    ProbeDirection,
    /// Commanded angle of a rotary axis, rad.
    RotaryPosition(RotaryAxis),
    /// The instant's time on the recording's clock, s.
    Time,
    /// Gravity in the robot's base frame, m/s² (from its base accelerometer; straight down the
    /// base's −z when the recording gives none).
    Gravity,
}

impl SignalKind {
    /// Signals the forward model computes itself for each reading (ranges, the points of each
    /// frame, the probing direction) rather than reading them from a recording.
    pub fn is_computed_by_model(&self) -> bool {
        matches!(
            self,
            SignalKind::TrackerRange
                | SignalKind::ImagePoint
                | SignalKind::MachinePoint
                | SignalKind::WorkpiecePoint
                | SignalKind::TargetPoint
                | SignalKind::CameraPoint
                | SignalKind::ProbeDirection
        )
    }
}

impl fmt::Display for SignalKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SignalKind::AxisPosition(a) => write!(f, "axis_position[{a}] (m)"),
            SignalKind::ApproachDirection(a) => write!(f, "approach_direction[{a}] (±1)"),
            SignalKind::AxisVelocity(a) => write!(f, "axis_velocity[{a}] (m/s)"),
            SignalKind::Temperature(s) => write!(f, "temperature[{s}] (°C)"),
            SignalKind::TemperatureHistory(s) => write!(f, "temperature_history[{s}] (s, °C)"),
            SignalKind::AirTemperature => write!(f, "air_temperature (°C)"),
            SignalKind::AirPressure => write!(f, "air_pressure (Pa)"),
            SignalKind::AirHumidity => write!(f, "air_humidity (%RH)"),
            SignalKind::TimeSincePowerOn => write!(f, "time_since_power_on (s)"),
            SignalKind::LoadForce => write!(f, "load_force (N)"),
            SignalKind::TrackerRange => write!(f, "tracker_range (m)"),
            SignalKind::ImagePoint => write!(f, "image_point (normalised)"),
            SignalKind::MachinePoint => write!(f, "machine_point (m, machine frame)"),
            SignalKind::WorkpiecePoint => write!(f, "workpiece_point (m, workpiece frame)"),
            SignalKind::TargetPoint => write!(f, "target_point (m, workpiece frame)"),
            SignalKind::CameraPoint => write!(f, "camera_point (m, camera frame)"),
            SignalKind::ProbeDirection => write!(f, "probe_direction (unit vector)"),
            SignalKind::RotaryPosition(a) => write!(f, "rotary_position[{}] (rad)", a.name()),
            SignalKind::Time => write!(f, "time (s, the recording's clock)"),
            SignalKind::Gravity => write!(f, "gravity (m/s², robot base frame)"),
        }
    }
}

/// Values of the signals at one instant. Missing values are `None`; a term that needs one
/// returns [`PhysicsError::MissingSignal`].
///
/// Points: one slot per frame a term acts in, so terms of different frames evaluated for one
/// reading never read each other's point (the forward model, crates/model, fills them:
/// `machine_point` before the machine-frame terms, `workpiece_point` before the workpiece terms, `target_point` before `tracker_pose`,
/// `camera_point` before `camera_scale`).
#[derive(Debug, Clone, Default)]
pub struct Signals {
    /// Time of the instant, s, on the recording's clock (a bag's: seconds since the Unix epoch;
    /// the twin's: seconds since the start of the shift). The clock of [`Self::timeline`].
    pub time: Option<f64>,
    pub axis_position: [Option<f64>; 3],
    pub approach_direction: [Option<f64>; 3],
    pub axis_velocity: [Option<f64>; 3],
    /// Each sensor's reading at this instant, °C.
    pub temperatures: BTreeMap<String, f64>,
    /// Every sensor's samples of the recording, shared by all its instants (cheap to clone);
    /// lagged temperatures read it up to [`Self::time`].
    pub timeline: Option<Arc<TemperatureTimeline>>,
    pub air_temperature: Option<f64>,
    pub air_pressure: Option<f64>,
    pub air_humidity: Option<f64>,
    pub time_since_power_on: Option<f64>,
    pub load_force: Option<Vector3<f64>>,
    pub tracker_range: Option<f64>,
    pub image_point: Option<Vector2<f64>>,
    /// Nominal tool point in the machine frame, m ([`SignalKind::MachinePoint`]).
    pub machine_point: Option<Vector3<f64>>,
    /// How far the target this reading sighted sits from the model's tool point: the recorded
    /// active tool offset (`/machine/tool_offset`) minus the model's `tool_offset`, machine
    /// frame, m — a tracker reflector moved on the spindle. None (or zero): the model's tool.
    /// The forward model adds it to the nominal tool point; an angular error's Abbe arm
    /// lengthens by it (that is what makes roll, pitch and yaw separable from straightness).
    pub tool_offset_shift: Option<Vector3<f64>>,
    /// Nominal feature position on the workpiece, workpiece frame, m ([`SignalKind::WorkpiecePoint`]).
    pub workpiece_point: Option<Vector3<f64>>,
    /// True point an instrument sights, workpiece (cell) frame, m ([`SignalKind::TargetPoint`]).
    pub target_point: Option<Vector3<f64>>,
    /// A point in the camera frame, m ([`SignalKind::CameraPoint`]).
    pub camera_point: Option<Vector3<f64>>,
    pub probe_direction: Option<Vector3<f64>>,
    /// Commanded angles of the rotary axes A, B, C (rad), where the machine has them.
    pub rotary_position: [Option<f64>; 3],
    /// Gravity in the robot's base frame, m/s², pointing down ([`SignalKind::Gravity`]): from the
    /// base's accelerometer; None means the base stands level.
    pub gravity: Option<Vector3<f64>>,
    /// Each accelerometer's reading (specific force, its own frame, m/s²: +9.81 along its up axis
    /// at rest), by sensor name.
    pub accelerations: BTreeMap<String, Vector3<f64>>,
    /// The placement of the instrument that took this reading (a recording's `setup` column):
    /// the forward model reads it with that placement's pose (`tracker_pose[<setup>]`). None:
    /// the instrument's only pose.
    pub setup: Option<std::sync::Arc<str>>,
}

/// Who asks for a signal, named in the error when it is missing. A term passes itself, so its
/// label (a formatted string, e.g. `angular[x:z]`) is built only when there is an error to name
/// it in: the accessors below run for every term at every reading, and formatting the label there
/// eagerly was most of the cost of a model evaluation without Jacobian.
pub trait TermLabel {
    fn term_label(&self) -> String;
}

impl TermLabel for str {
    fn term_label(&self) -> String {
        self.to_string()
    }
}

impl TermLabel for String {
    fn term_label(&self) -> String {
        self.clone()
    }
}

impl<T: crate::term::PhysicsTerm + ?Sized> TermLabel for T {
    fn term_label(&self) -> String {
        self.label()
    }
}

fn missing(term: &(impl TermLabel + ?Sized), kind: SignalKind) -> PhysicsError {
    PhysicsError::MissingSignal {
        term: term.term_label(),
        signal: kind.to_string(),
    }
}

impl Signals {
    /// Set all three commanded axis positions (m).
    pub fn with_positions(mut self, p: Vector3<f64>) -> Self {
        self.axis_position = [Some(p.x), Some(p.y), Some(p.z)];
        self
    }
    #[inline]
    pub fn position(&self, term: &(impl TermLabel + ?Sized), a: Axis) -> Result<f64, PhysicsError> {
        self.axis_position[a.index()].ok_or_else(|| missing(term, SignalKind::AxisPosition(a)))
    }
    pub fn approach(&self, term: &(impl TermLabel + ?Sized), a: Axis) -> Result<f64, PhysicsError> {
        let s = self.approach_direction[a.index()]
            .ok_or_else(|| missing(term, SignalKind::ApproachDirection(a)))?;
        if s == 1.0 || s == -1.0 {
            Ok(s)
        } else {
            Err(PhysicsError::BadSignal {
                term: term.term_label(),
                signal: SignalKind::ApproachDirection(a).to_string(),
                reason: format!("must be +1 or -1, got {s}"),
            })
        }
    }
    pub fn velocity(&self, term: &(impl TermLabel + ?Sized)) -> Result<Vector3<f64>, PhysicsError> {
        let mut v = Vector3::zeros();
        for a in Axis::ALL {
            v[a.index()] = self.axis_velocity[a.index()]
                .ok_or_else(|| missing(term, SignalKind::AxisVelocity(a)))?;
        }
        Ok(v)
    }
    pub fn temperature(
        &self,
        term: &(impl TermLabel + ?Sized),
        sensor: &str,
    ) -> Result<f64, PhysicsError> {
        self.temperatures
            .get(sensor)
            .copied()
            .ok_or_else(|| missing(term, SignalKind::Temperature(sensor.to_string())))
    }
    /// (T_f °C, ∂T_f/∂τ K/s): the first-order lag with time constant `tau` (s) of the sensor's
    /// samples in the timeline up to [`Self::time`] (all of them when the time is not set).
    pub fn lagged_temperature(
        &self,
        term: &(impl TermLabel + ?Sized),
        sensor: &str,
        tau: f64,
    ) -> Result<(f64, f64), PhysicsError> {
        let kind = || SignalKind::TemperatureHistory(sensor.to_string());
        let timeline = self
            .timeline
            .as_ref()
            .ok_or_else(|| missing(term, kind()))?;
        timeline
            .lagged(sensor, self.time, tau)
            .map_err(|why| match why {
                LagUnavailable::UnknownSensor => missing(term, kind()),
                LagUnavailable::NoSampleYet { first } => PhysicsError::BadSignal {
                    term: term.term_label(),
                    signal: kind().to_string(),
                    reason: match first {
                        Some(first) => format!(
                            "no sample at or before t = {} s (the first is at {first} s)",
                            self.time.unwrap_or(f64::NAN)
                        ),
                        None => "the sensor has no samples".into(),
                    },
                },
                LagUnavailable::BadTimeConstant => PhysicsError::InvalidInput {
                    what: format!("term `{}`: time_constant", term.term_label()),
                    reason: format!("must be > 0 s and finite, got {tau}"),
                },
            })
    }
    pub fn air(&self, term: &(impl TermLabel + ?Sized)) -> Result<(f64, f64, f64), PhysicsError> {
        Ok((
            self.air_temperature
                .ok_or_else(|| missing(term, SignalKind::AirTemperature))?,
            self.air_pressure
                .ok_or_else(|| missing(term, SignalKind::AirPressure))?,
            self.air_humidity
                .ok_or_else(|| missing(term, SignalKind::AirHumidity))?,
        ))
    }
    pub fn time_on(&self, term: &(impl TermLabel + ?Sized)) -> Result<f64, PhysicsError> {
        self.time_since_power_on
            .ok_or_else(|| missing(term, SignalKind::TimeSincePowerOn))
    }
    pub fn load(&self, term: &(impl TermLabel + ?Sized)) -> Result<Vector3<f64>, PhysicsError> {
        self.load_force
            .ok_or_else(|| missing(term, SignalKind::LoadForce))
    }
    pub fn range(&self, term: &(impl TermLabel + ?Sized)) -> Result<f64, PhysicsError> {
        self.tracker_range
            .ok_or_else(|| missing(term, SignalKind::TrackerRange))
    }
    pub fn image(&self, term: &(impl TermLabel + ?Sized)) -> Result<Vector2<f64>, PhysicsError> {
        self.image_point
            .ok_or_else(|| missing(term, SignalKind::ImagePoint))
    }
    pub fn machine(&self, term: &(impl TermLabel + ?Sized)) -> Result<Vector3<f64>, PhysicsError> {
        self.machine_point
            .ok_or_else(|| missing(term, SignalKind::MachinePoint))
    }
    pub fn workpiece(
        &self,
        term: &(impl TermLabel + ?Sized),
    ) -> Result<Vector3<f64>, PhysicsError> {
        self.workpiece_point
            .ok_or_else(|| missing(term, SignalKind::WorkpiecePoint))
    }
    pub fn target(&self, term: &(impl TermLabel + ?Sized)) -> Result<Vector3<f64>, PhysicsError> {
        self.target_point
            .ok_or_else(|| missing(term, SignalKind::TargetPoint))
    }
    pub fn camera(&self, term: &(impl TermLabel + ?Sized)) -> Result<Vector3<f64>, PhysicsError> {
        self.camera_point
            .ok_or_else(|| missing(term, SignalKind::CameraPoint))
    }
    pub fn rotary(
        &self,
        term: &(impl TermLabel + ?Sized),
        a: RotaryAxis,
    ) -> Result<f64, PhysicsError> {
        self.rotary_position[a.index()].ok_or_else(|| missing(term, SignalKind::RotaryPosition(a)))
    }
    pub fn probe_dir(
        &self,
        term: &(impl TermLabel + ?Sized),
    ) -> Result<Vector3<f64>, PhysicsError> {
        let u = self
            .probe_direction
            .ok_or_else(|| missing(term, SignalKind::ProbeDirection))?;
        let n = u.norm();
        if !(n.is_finite() && (n - 1.0).abs() < 1e-6) {
            return Err(PhysicsError::BadSignal {
                term: term.term_label(),
                signal: SignalKind::ProbeDirection.to_string(),
                reason: format!("must be a unit vector, norm is {n}"),
            });
        }
        Ok(u)
    }
}
