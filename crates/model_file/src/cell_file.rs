//! The cell description file as written (YAML, serde, every section `deny_unknown_fields`).
//! Values are [`Quantity`]s (number in the documented SI unit, or text with a unit). The
//! validated forms are [`crate::CellModel`] (the model) and crates/twin's `Cell` (a cell to
//! simulate); see crates/twin `examples/cells/*.yaml` for commented files.
//!
//! A **stationing program** (a serial arm measured by a levelled instrument from several setups,
//! crates/twin `stationing`; `crates/twin/examples/cells/mobile_manipulator.yaml`) adds these
//! keys, each refused in a cell without `program.stationing`:
//! * `program.stationing: {levels, configurations: [{name, joints}], spread, fit_points,
//!   check_points, groups_per_setup, min_tool_height, seed}` ([`StationingSection`]) — instead
//!   of `joints`/`poses`; `feed_rate`, `rotary_rate` and `dwell` time it, one pass;
//! * `sensors.tracker.setups: [{name, translation, yaw}]` and `point_noise` — the instrument's
//!   placements in the base's levelled frame and its σ per axis (`levelled: true`, `tilt_sigma`
//!   as a model file reads them; no pose, rate or noise model of a tracker);
//! * `environment.ground_tilt: {roll, pitch}` — the base's tilt from level;
//! * `sensors.accelerometers[i].noise`, `bias`, `misalignment` — the sensor's truth (a model
//!   file may carry them; the loader reads only `name` and `link`).

use std::collections::BTreeMap;

use metrocell_physics::{ConfigValue, EstimationConfig, TermConfig};
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
    /// Required to simulate only what the cell has; a model file may leave it out.
    #[serde(default)]
    pub sensors: SensorsSection,
    /// Required to simulate; optional in a model file (`metrocell calibrate` reads the
    /// environment from the recording).
    #[serde(default)]
    pub environment: Option<EnvironmentSection>,
    /// Required to simulate; optional in a model file.
    #[serde(default)]
    pub program: Option<ProgramSection>,
    /// The machine's true error terms (physics catalog configs). The same file with fewer
    /// terms is a user's nominal model.
    #[serde(default)]
    pub terms: Vec<TermConfig>,
    /// For an estimator of this cell: per term label (`positioning[x]`, `tracker_pose`, …)
    /// the free parameters and priors, `{free: [c0, c1], priors: {c0: {value: 0 um, sigma: 5 um}}}`.
    #[serde(default)]
    pub estimation: BTreeMap<String, EstimationConfig>,
    /// Standard uncertainties (k = 1) of fitted parameters, per term label and parameter
    /// (`{"thermal_scale[x]": {alpha: 4.1e-7 1/K}}`), as `metrocell calibrate` writes them next
    /// to the fitted values. Read back by the model loader; the simulator ignores it.
    #[serde(default)]
    pub uncertainty: BTreeMap<String, BTreeMap<String, ConfigValue>>,
    /// What the fit that wrote this file saw (records, residuals, what was not identifiable);
    /// free-form, for the reader. The simulator and the loader ignore it.
    #[serde(default)]
    pub fit: Option<serde_yaml::Value>,
    /// Test-only, non-physical structures (a drift cycling in time, a local bump in the
    /// workspace) for the concealed-effect suite: see crates/twin `disturbance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbances: Option<DisturbanceSection>,
}

/// Machine families, all simulated: `cartesian` (3 axes in a stacking order), `delta` (linear
/// delta), `five_axis` (B/C tilting-rotary table, crates/kinematics `FiveAxisGeometry`) and
/// `serial_arm` (DH table or URDF chain).
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
    /// Five-axis B/C table geometry (crates/kinematics `FiveAxisGeometry`).
    #[serde(default)]
    pub five_axis: Option<FiveAxisSection>,
    /// Serial arm: DH table or URDF, base and tool frames, joint limits.
    #[serde(default)]
    pub serial_arm: Option<SerialArmSection>,
    /// Travel of each axis, `[min, max]` (m): Cartesian axes, the delta's effector box, the
    /// five-axis X, Y, Z. Not used by a serial arm (its limits are `serial_arm.joint_limits`).
    #[serde(default)]
    pub travel: Option<TravelSection>,
    /// Tool tip (or tracker target) relative to the tool-carrying body at q = 0 (m).
    #[serde(default)]
    pub tool_offset: Option<[Quantity; 3]>,
    /// The twin's axes following their command through seed 004's dynamics and a position loop
    /// (crates/twin `following_error`), by axis name (`x`, `y`, `z`): a simulation option of the
    /// twin, which models never read.
    #[serde(default)]
    pub servo: Option<BTreeMap<String, ServoSection>>,
}

/// One axis of `machine.servo`: seed 004's plant (J θ̈ + b θ̇ + μ·sgn(θ̇)·r·N = T) and the loop
/// T = k_p (θ_c − θ) + k_d (θ̇_c − θ̇) + b θ̇_c (crates/kinematics `axis_servo`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoSection {
    /// J, reflected to the motor (kg m^2), the translating mass's m·r² included.
    pub inertia: Quantity,
    /// b, viscous (N m s/rad).
    pub damping: Quantity,
    /// μ, Coulomb friction coefficient.
    pub friction: f64,
    /// N, the normal force the friction acts on (N).
    pub normal_force: Quantity,
    /// r, the radius the friction acts at: the drum's for a belt, the screw's (m).
    pub radius: Quantity,
    /// Travel per motor radian (m/rad); default r (a belt). A screw: r·tan λ.
    #[serde(default)]
    pub lead: Option<Quantity>,
    /// k_p (N m/rad).
    pub kp: Quantity,
    /// k_d (N m s/rad); default critical damping 2√(k_p J) − b.
    #[serde(default)]
    pub kd: Option<Quantity>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeltaSection {
    /// `DELTA_DIAGONAL_ROD` (m).
    pub rod_length: Quantity,
    /// `DELTA_RADIUS` (m).
    pub radius: Quantity,
}

/// Five-axis table/table machine (seed 004). Axis coordinates of the program: X, Y, Z (m) and
/// B, C (rad); X = DH d2, Y = DH d1, Z = −d3 (ISO: +Z moves the tool up, away from the table).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FiveAxisSection {
    /// DH constant d0: height of the spindle gauge point at Z = 0 (m).
    pub d0: Quantity,
    /// Gauge point to tool tip, along −z (m).
    pub tool_length: Quantity,
    /// A point on the B axis, machine frame (m; default origin).
    #[serde(default)]
    pub b_pivot: Option<[Quantity; 3]>,
    /// B pivot → a point on the C axis, cradle frame at B = 0 (m; default zero).
    #[serde(default)]
    pub c_offset: Option<[Quantity; 3]>,
    /// C-axis point → workpiece origin, table frame at C = 0 (m; default zero).
    #[serde(default)]
    pub workpiece_offset: Option<[Quantity; 3]>,
    /// `[min, max]` of B (rad); default ±90°.
    #[serde(default)]
    pub b_limits: Option<[Quantity; 2]>,
    /// `[min, max]` of C (rad); default ±360°.
    #[serde(default)]
    pub c_limits: Option<[Quantity; 2]>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DhConventionName {
    Standard,
    Modified,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKindName {
    #[default]
    Revolute,
    Prismatic,
    Fixed,
}

/// One DH row: θ, α (rad) and d, a (m); a modified row holds a_{i−1}, α_{i−1} in `a`, `alpha`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhRowSection {
    #[serde(default)]
    pub theta: Option<Quantity>,
    #[serde(default)]
    pub d: Option<Quantity>,
    #[serde(default)]
    pub a: Option<Quantity>,
    #[serde(default)]
    pub alpha: Option<Quantity>,
    #[serde(default)]
    pub joint: JointKindName,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhSection {
    pub convention: DhConventionName,
    pub rows: Vec<DhRowSection>,
}

/// A URDF chain; `path` is relative to the cell file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UrdfSection {
    pub path: String,
    pub root_link: String,
    pub tip_link: String,
}

/// Serial arm (crates/kinematics `SerialChain`): exactly one of `dh` and `urdf`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SerialArmSection {
    #[serde(default)]
    pub dh: Option<DhSection>,
    #[serde(default)]
    pub urdf: Option<UrdfSection>,
    /// Arm base in the cell (workpiece/world) frame; default identity.
    #[serde(default)]
    pub base: Option<PoseSection>,
    /// Tool point (tracker target) relative to the last link; default identity.
    #[serde(default)]
    pub tool: Option<PoseSection>,
    /// `[min, max]` per movable joint (rad or m); absent: unlimited.
    #[serde(default)]
    pub joint_limits: Vec<[Quantity; 2]>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TravelSection {
    pub x: [Quantity; 2],
    pub y: [Quantity; 2],
    pub z: [Quantity; 2],
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
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
    /// 3-axis accelerometers on a serial arm (URDF): each one's `/imu/<name>` readings and the
    /// link it sits on.
    #[serde(default)]
    pub accelerometers: Vec<AccelerometerSection>,
}

/// An accelerometer on a serial arm: `name` as in `/imu/<name>` (the import layout's
/// `accel.<name>.x|y|z`), `link` a link of the arm's URDF whose frame is the sensor's.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AccelerometerSection {
    pub name: String,
    pub link: String,
    /// Simulation only (a model file may give them; the loader ignores them): σ of each axis's
    /// white noise (m/s²), …
    #[serde(default)]
    pub noise: Option<Quantity>,
    /// … the sensor's constant bias per axis, its own frame (m/s²), …
    #[serde(default)]
    pub bias: Option<[Quantity; 3]>,
    /// … and its mounting misalignment: the true sensor frame is the link's turned by this
    /// rotation vector (rad, the link's axes).
    #[serde(default)]
    pub misalignment: Option<[Quantity; 3]>,
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
    /// Where the tracker stands. Required to simulate; a model file may leave it out when the
    /// pose is unknown (points in the tracker's frame: the pose is registered from each
    /// recording), e.g. a tracker whose warm-up `diagnose` found.
    #[serde(default)]
    pub pose: Option<PoseSection>,
    /// Sample rate (Hz). Required to simulate; a model file may leave the noise model out.
    #[serde(default)]
    pub rate: Option<Quantity>,
    /// σ_ρ = constant + per_metre·ρ. Required to simulate.
    #[serde(default)]
    pub range_noise: Option<RangeNoiseSection>,
    /// σ of azimuth and of elevation (rad). Required to simulate.
    #[serde(default)]
    pub angular_noise: Option<Quantity>,
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
    /// The instrument levels itself (a total station's compensator, a tracker's level): its z
    /// is straight up to `tilt_sigma`. A model file with it fits each placement's tilt with a
    /// prior of that σ about level and the base's tilt from level once for all placements
    /// (`base_tilt`); without it every placement's pose is six free numbers.
    #[serde(default)]
    pub levelled: bool,
    /// σ of a levelled instrument's residual tilt about each horizontal axis (rad; default
    /// 50 µrad, a tracker's level: a total station's compensator does better, give yours).
    #[serde(default)]
    pub tilt_sigma: Option<Quantity>,
    /// A stationing program's instrument (`program.stationing`, simulation only): where it is
    /// set up, each placement in the base's levelled frame (`crate::stationing`) …
    #[serde(default)]
    pub setups: Vec<SetupSection>,
    /// … and the σ of its point noise on each axis of its frame (m), centring and EDM and
    /// angles together (a total station with a 360° prism: about 0.75 mm).
    #[serde(default)]
    pub point_noise: Option<Quantity>,
}

/// One placement of a stationing program's instrument: its origin in the base's levelled
/// frame (x the base's x turned by the ground's tilt only, z straight up) and its yaw about z;
/// its residual tilt is drawn per recording within `tilt_sigma`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetupSection {
    pub name: String,
    pub translation: [Quantity; 3],
    #[serde(default)]
    pub yaw: Option<Quantity>,
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
    /// Camera frame relative to the tool frame (axes: workpiece on cartesian and delta, machine
    /// on five_axis, the arm's tool frame on serial_arm); the camera turns with the tool.
    pub mount: PoseSection,
    /// Delay after the start of each dwell at which a frame is requested (s).
    #[serde(default)]
    pub delay: Option<Quantity>,
    /// Lens and sensor (pinhole + Brown–Conrady); absent: the simulator's default camera.
    #[serde(default)]
    pub intrinsics: Option<IntrinsicsSection>,
}

/// Pinhole intrinsics in pixels (OpenCV convention: centre of the top-left pixel at (0, 0)).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntrinsicsSection {
    pub width: u32,
    pub height: u32,
    pub fx: Quantity,
    pub fy: Quantity,
    pub cx: Quantity,
    pub cy: Quantity,
    /// Lens model, with ROS camera_info's names: `plumb_bob` (Brown–Conrady, the default) or
    /// `equidistant` (fisheye, OpenCV's `cv::fisheye`).
    #[serde(default)]
    pub model: Option<String>,
    /// Coefficients in OpenCV order: plumb_bob k1 k2 p1 p2 k3, equidistant k1 k2 k3 k4 (missing
    /// trailing ones are 0).
    #[serde(default)]
    pub distortion: Vec<f64>,
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
    /// A serial arm's base tilted from level (a robot on a pallet, a seesaw, a ramp):
    /// R = Rx(roll)·Ry(pitch) turns the base into the level frame, so gravity in the base is
    /// Rᵀ·(0, 0, −g) (`Signals::gravity`) and the truth's `base_tilt` is (roll, pitch).
    /// `metrocell sim --ground-tilt` overrides it. Absent: level.
    #[serde(default)]
    pub ground_tilt: Option<GroundTiltSection>,
}

/// Tilt of the ground under the robot's base (rad): roll about x first, pitch about y.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundTiltSection {
    #[serde(default)]
    pub roll: Option<Quantity>,
    #[serde(default)]
    pub pitch: Option<Quantity>,
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
    /// … or an explicit list (m) (cartesian, delta) …
    #[serde(default)]
    pub points: Vec<[Quantity; 3]>,
    /// … or joint targets: five_axis `[X, Y, Z, B, C]` (m, m, m, rad, rad), serial_arm one
    /// value per movable joint (rad or m) …
    #[serde(default)]
    pub joints: Vec<Vec<Quantity>>,
    /// … or tool poses solved by the family's inverse kinematics (five_axis, serial_arm).
    #[serde(default)]
    pub poses: Vec<PoseTargetSection>,
    /// Speed of rotary joints in moves (rad/s; five_axis and serial_arm; default 30 deg/s).
    #[serde(default)]
    pub rotary_rate: Option<Quantity>,
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
    /// Home as joint values (five_axis, serial_arm; default the first target).
    #[serde(default)]
    pub home_joints: Option<Vec<Quantity>>,
    /// … or a stationing program of a serial arm measured by a levelled instrument from
    /// several setups (`crate::stationing_program`): groups of fit and check waypoints.
    #[serde(default)]
    pub stationing: Option<StationingSection>,
}

/// A stationing program: one group per (column level, arm configuration), level-major; each
/// group's waypoints are the configuration's joints perturbed with a seeded RNG, the first
/// joint variable (the column) at the level; `fit_points` of them chosen far apart are `fit`,
/// the others `check`; `groups_per_setup` consecutive groups are measured from each setup of
/// `sensors.tracker.setups` in turn.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationingSection {
    /// Values of the arm's first joint variable (the lifting column), m or rad.
    pub levels: Vec<Quantity>,
    /// The other joint variables of each configuration (a solution space: elbow up/down, …).
    pub configurations: Vec<ConfigurationSection>,
    /// Half-width of the uniform perturbation of each of those joints (rad or m).
    pub spread: Vec<Quantity>,
    pub fit_points: u32,
    pub check_points: u32,
    /// Consecutive groups measured from one setup (default 1).
    #[serde(default)]
    pub groups_per_setup: Option<u32>,
    /// Waypoints whose nominal tool point is lower than this in the base frame are drawn
    /// again (m; default: no limit).
    #[serde(default)]
    pub min_tool_height: Option<Quantity>,
    /// Seed of the plan (the same waypoints whatever the simulation's noise seed; default 1).
    #[serde(default)]
    pub seed: Option<u64>,
}

/// An arm configuration of a stationing program.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigurationSection {
    pub name: String,
    pub joints: Vec<Quantity>,
}

/// A tool pose target. Five-axis: tool tip `position` and tool `axis` (tip → spindle) in the
/// workpiece frame (default axis +z). Serial arm: tool point `position` in the cell frame and,
/// optionally, its orientation `euler_xyz` (R = Rx·Ry·Rz); without it the IK is position-only.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseTargetSection {
    pub position: [Quantity; 3],
    #[serde(default)]
    pub axis: Option<[f64; 3]>,
    #[serde(default)]
    pub euler_xyz: Option<[Quantity; 3]>,
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

// `disturbances:` — test-only, non-physical structures (crates/twin `disturbance`).

/// The `disturbances` section of a cell file.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisturbanceSection {
    #[serde(default)]
    pub time_cycles: Vec<TimeCycleSection>,
    #[serde(default)]
    pub workspace_bumps: Vec<WorkspaceBumpSection>,
}

/// A drift that cycles in time: `amplitude·sin(2π t/period + phase)`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeCycleSection {
    /// Peak displacement vector (m).
    pub amplitude: [Quantity; 3],
    /// Period (s).
    pub period: Quantity,
    /// Phase at t = 0 (rad; default 0).
    #[serde(default)]
    pub phase: Option<Quantity>,
}

/// A local bump over the workspace: `amplitude·exp(−|q − centre|²/(2·width²))`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorkspaceBumpSection {
    /// Peak displacement vector at the centre (m).
    pub amplitude: [Quantity; 3],
    /// Centre in axis coordinates (commanded x, y, z; m).
    pub centre: [Quantity; 3],
    /// Gaussian width σ (m).
    pub width: Quantity,
}
