//! The cell description file as written (YAML, serde, every section `deny_unknown_fields`).
//! Values are [`Quantity`]s (number in the documented SI unit, or text with a unit). The
//! validated, SI form is [`crate::cell::Cell`]; see `examples/cells/*.yaml` for commented files.

use std::collections::BTreeMap;

use metrocell_physics::{ConfigValue, TermConfig};
use serde::{Deserialize, Serialize};

use crate::quantity::Quantity;

/// Top level of a cell file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellFile {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub machine: MachineSection,
    pub sensors: SensorsSection,
    pub environment: EnvironmentSection,
    pub program: ProgramSection,
    /// The machine's true error terms (physics catalog configs). The same file with fewer
    /// terms is a user's nominal model.
    #[serde(default)]
    pub terms: Vec<TermConfig>,
}

/// Machine families. `cartesian` and `delta` are simulated; `five_axis` and `serial_arm` are
/// accepted by the schema so a file can name them (crates/kinematics has their chains), and are
/// rejected at validation with a clear message until the twin wires them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MachineFamily {
    Cartesian,
    FiveAxis,
    Delta,
    SerialArm,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineSection {
    pub family: MachineFamily,
    /// Cartesian stacking order, e.g. `XFYZ` (crates/kinematics convention).
    #[serde(default)]
    pub stacking: Option<String>,
    /// Linear delta nominal geometry (Marlin conventions, crates/kinematics `DeltaGeometry`).
    #[serde(default)]
    pub delta: Option<DeltaSection>,
    /// Travel of each axis, `[min, max]` (m).
    pub travel: TravelSection,
    /// Tool tip (or tracker target) relative to the tool-carrying body at q = 0 (m).
    #[serde(default)]
    pub tool_offset: Option<[Quantity; 3]>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeltaSection {
    /// `DELTA_DIAGONAL_ROD` (m).
    pub rod_length: Quantity,
    /// `DELTA_RADIUS` (m).
    pub radius: Quantity,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TravelSection {
    pub x: [Quantity; 2],
    pub y: [Quantity; 2],
    pub z: [Quantity; 2],
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorsSection {
    #[serde(default)]
    pub tracker: Option<TrackerSection>,
    #[serde(default)]
    pub thermocouples: Vec<ThermocoupleSection>,
    #[serde(default)]
    pub machine_state: Option<MachineStateSection>,
    #[serde(default)]
    pub probe: Option<ProbeSection>,
    #[serde(default)]
    pub camera: Option<CameraSection>,
}

/// Pose of an instrument frame in the workpiece (table) frame: `p_wp = R·p_inst + t`,
/// `R = Rx(a)·Ry(b)·Rz(c)` (Euler XYZ, thesis P3/P5).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSection {
    pub translation: [Quantity; 3],
    #[serde(default)]
    pub euler_xyz: Option<[Quantity; 3]>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackerSection {
    pub pose: PoseSection,
    /// Sample rate (Hz).
    pub rate: Quantity,
    /// σ_ρ = constant + per_metre·ρ.
    pub range_noise: RangeNoiseSection,
    /// σ of azimuth and of elevation (rad).
    pub angular_noise: Quantity,
    /// Warm-up drift of the range, the physics `tracker_warmup` parameters
    /// (`offset` A, `amplitude` B, `time_constant` τ). Absent: no drift.
    #[serde(default)]
    pub warmup: Option<BTreeMap<String, ConfigValue>>,
    /// Time the tracker had been on when the shift starts (s).
    #[serde(default)]
    pub powered_on_before_start: Option<Quantity>,
    /// Weather station of the tracker (its reading sets the index the tracker applies).
    #[serde(default)]
    pub station: Option<StationSection>,
    /// Turbulent air on the beam: scatter inflation in time windows.
    #[serde(default)]
    pub turbulence: Vec<TurbulenceWindow>,
    /// Beam breaks (dropped samples).
    #[serde(default)]
    pub beam_breaks: Option<BeamBreakSection>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeNoiseSection {
    /// a (m).
    pub constant: Quantity,
    /// b (dimensionless, e.g. `0.8 um/m`).
    pub per_metre: Quantity,
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationSection {
    /// Station reading minus the true ambient (K), the concealed part of the refraction error.
    #[serde(default)]
    pub temperature_bias: Option<Quantity>,
    #[serde(default)]
    pub pressure_bias: Option<Quantity>,
    #[serde(default)]
    pub humidity_bias: Option<Quantity>,
    /// White noise on each station reading (σ).
    #[serde(default)]
    pub temperature_noise: Option<Quantity>,
    #[serde(default)]
    pub pressure_noise: Option<Quantity>,
    #[serde(default)]
    pub humidity_noise: Option<Quantity>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurbulenceWindow {
    pub start: Quantity,
    pub end: Quantity,
    /// c of σ = √((a + bρ)² + (cρ)²) (physics `turbulence`; dimensionless, e.g. `30 um/m`).
    pub coefficient: Quantity,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamBreakSection {
    /// Mean number of breaks per hour (Poisson).
    pub per_hour: f64,
    /// Mean duration of a break (exponential), s.
    pub mean_duration: Quantity,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermocoupleSection {
    pub name: String,
    /// `ambient` or the name of a structure node of `environment.nodes`.
    pub location: String,
    /// σ of the white noise (K).
    pub noise: Quantity,
    /// Reading minus truth (K); concealed unless the user's model knows it.
    #[serde(default)]
    pub offset: Option<Quantity>,
    /// Calibration uncertainty the sensor states (K, 1σ); enters the stated variance.
    #[serde(default)]
    pub calibration_uncertainty: Option<Quantity>,
    /// Sample rate (Hz).
    pub rate: Quantity,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineStateSection {
    pub rate: Quantity,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSection {
    /// Probing directions at each program point (machine frame; normalised on load).
    pub directions: Vec<[f64; 3]>,
    /// Time between hits within a dwell (s).
    pub hit_interval: Quantity,
    /// σ of the recorded point, each axis (m).
    pub noise: Quantity,
    /// Pretravel lobing: a physics `probe_pretravel` config without `id`
    /// (`options: {lobes}`, `params: {mean, lobe_cos, lobe_sin, vertical}`).
    #[serde(default)]
    pub pretravel: Option<PretravelSection>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PretravelSection {
    #[serde(default)]
    pub options: BTreeMap<String, ConfigValue>,
    #[serde(default)]
    pub params: BTreeMap<String, ConfigValue>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// Camera frame relative to the tool tip, in the workpiece frame axes.
    pub mount: PoseSection,
    /// Delay after the start of each dwell at which a frame is requested (s).
    #[serde(default)]
    pub delay: Option<Quantity>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSection {
    pub ambient: AmbientSection,
    #[serde(default)]
    pub heat_sources: Vec<HeatSourceSection>,
    #[serde(default)]
    pub nodes: Vec<NodeSection>,
    /// Integration step of the lumped thermal model (s, default 1 s).
    #[serde(default)]
    pub thermal_step: Option<Quantity>,
    pub air: AirSection,
    /// Constant load force for `compliance` terms (N, machine frame).
    #[serde(default)]
    pub load_force: Option<[Quantity; 3]>,
}

/// Physics `AmbientCycle`: T = mean + amplitude·sin(2πt/period + phase) + drift·t + walk.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmbientSection {
    pub mean: Quantity,
    #[serde(default)]
    pub amplitude: Option<Quantity>,
    #[serde(default)]
    pub period: Option<Quantity>,
    #[serde(default)]
    pub phase: Option<Quantity>,
    /// K/s (e.g. `0.1 K/h`).
    #[serde(default)]
    pub drift: Option<Quantity>,
    /// Random-walk intensity, K/√s (number only).
    #[serde(default)]
    pub walk_std: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeatSourceSection {
    pub name: String,
    pub duty: Vec<DutySection>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DutySection {
    pub start: Quantity,
    pub end: Quantity,
    pub level: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSection {
    pub name: String,
    pub time_constant: Quantity,
    /// Heat source name → steady-state rise at full duty (K).
    #[serde(default)]
    pub heating: BTreeMap<String, Quantity>,
    /// Initial temperature (°C); default: the ambient at t = 0.
    #[serde(default)]
    pub initial: Option<Quantity>,
}

/// True air on the tracker beam.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AirSection {
    pub pressure: Quantity,
    /// %RH.
    pub humidity: f64,
    /// Mean beam air temperature minus the ambient (K).
    #[serde(default)]
    pub beam_temperature_offset: Option<Quantity>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VisitOrder {
    Raster,
    #[default]
    Serpentine,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProgramSection {
    /// A grid of commanded axis positions …
    #[serde(default)]
    pub grid: Option<GridSection>,
    /// … or an explicit list (m).
    #[serde(default)]
    pub points: Vec<[Quantity; 3]>,
    #[serde(default)]
    pub order: VisitOrder,
    /// Path speed of moves (m/s).
    pub feed_rate: Quantity,
    /// Dwell at each point (s).
    pub dwell: Quantity,
    /// Time before the first cycle (s, default 0).
    #[serde(default)]
    pub start: Option<Quantity>,
    /// Number of cycles; absent: repeat until the end of the simulation.
    #[serde(default)]
    pub cycles: Option<u32>,
    /// Start-to-start time of cycles (s); a longer cycle starts the next one at once.
    #[serde(default)]
    pub cycle_interval: Option<Quantity>,
    /// Home position, start and end of every cycle (m, default the first point).
    #[serde(default)]
    pub home: Option<[Quantity; 3]>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSection {
    pub x: GridAxis,
    pub y: GridAxis,
    pub z: GridAxis,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridAxis {
    pub from: Quantity,
    pub to: Quantity,
    pub count: u32,
}
