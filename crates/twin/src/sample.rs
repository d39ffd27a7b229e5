//! The typed samples a simulation streams, and the ground truth that goes with each.
//!
//! Units SI (m, rad, s, Pa); temperatures °C; humidity %RH. Times `t` are seconds from the start
//! of the shift. Tracker points are in the tracker frame; probe and camera points in the
//! workpiece frame (which coincides with the machine frame at q = 0).

use std::sync::Arc;

use nalgebra::{Matrix3, Vector2, Vector3};

/// Tracker sample status.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrackerStatus {
    /// A valid measurement.
    Ok,
    /// The beam was broken: the sample was dropped; every measured field is NaN.
    BeamBroken,
}

/// One laser-tracker reading (see [`crate::tracker_model`] for the model and conventions).
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerSample {
    pub t: f64,
    /// Program point index while the machine dwells at a point; `None` while it moves or idles.
    pub target_id: Option<u32>,
    /// Program cycle (0-based) or `None` outside cycles.
    pub cycle: Option<u32>,
    /// Measured target position in the tracker frame (m).
    pub point: Vector3<f64>,
    pub range: f64,
    pub azimuth: f64,
    pub elevation: f64,
    /// Stated covariance of `point` (m²).
    pub covariance: Matrix3<f64>,
    /// Weather-station readings the tracker used: °C, Pa, %RH.
    pub air_temperature: f64,
    pub air_pressure: f64,
    pub air_humidity: f64,
    /// Refractive index the tracker applied (shop-floor Edlén of the station readings).
    pub refractive_index: f64,
    pub status: TrackerStatus,
}

/// One thermocouple reading.
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureSample {
    pub t: f64,
    pub sensor: Arc<str>,
    /// °C.
    pub value: f64,
    /// Stated variance (K²): noise² + calibration uncertainty².
    pub variance: f64,
}

/// Commanded and actual axis positions.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineStateSample {
    pub t: f64,
    /// Joint names, shared by every sample (`x y z`; five-axis `x y z b c`; arm joint names).
    pub names: Arc<[String]>,
    /// Commanded joint values (m or rad).
    pub commanded: Vec<f64>,
    /// Commanded joint velocities (m/s or rad/s): the program's, constant along a move, 0 at a
    /// dwell and while idle.
    pub commanded_velocity: Vec<f64>,
    /// Actual values: cartesian/delta and five-axis X, Y, Z commanded + the true terms'
    /// displacement (tool relative to workpiece); rotary B, C as commanded; arm joints
    /// commanded + their true zero offsets (`joint_offset`).
    pub actual: Vec<f64>,
}

/// A touch-probe trigger.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeHitSample {
    pub t: f64,
    pub target_id: u32,
    pub cycle: u32,
    /// Index into the probe's configured directions.
    pub direction_index: u32,
    /// Unit probing (approach) direction, machine frame.
    pub direction: Vector3<f64>,
    /// Nominal contact point (the program point on a perfect artefact), workpiece frame (m).
    pub nominal: Vector3<f64>,
    /// Point the machine recorded at the trigger (nominal kinematics of the axis reading), m.
    pub recorded: Vector3<f64>,
    /// Stated covariance of `recorded` (m²), isotropic noise σ².
    pub covariance: Matrix3<f64>,
}

/// A request to render a camera frame (rendering is another component's job).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFrameRequest {
    pub t: f64,
    pub target_id: u32,
    pub cycle: u32,
    /// True camera pose in the frame tool points are reported in (workpiece; cell for an arm):
    /// `p = rotation·p_cam + position`, with the camera optical frame (x right, y down, z
    /// forward). The camera rides on the tool, so this is the true tool pose followed by the
    /// cell's `sensors.camera.mount`.
    pub position: Vector3<f64>,
    pub rotation: Matrix3<f64>,
    /// Nominal camera pose (the commanded tool pose followed by the mount), same convention.
    pub nominal_position: Vector3<f64>,
    pub nominal_rotation: Matrix3<f64>,
    /// The fiducial plate's pose, same frame: `p = plate_rotation·p_plate + plate_position`
    /// ([`crate::fiducial_plate`]): in front of the nominal camera, moved by the workpiece terms'
    /// displacement at its centre. A renderer draws this rigid plate; the part's small rotation
    /// and expansion across the 50 mm plate (first order in the workpiece terms) are in
    /// `corners`, not in a rigid pose.
    pub plate_position: Vector3<f64>,
    pub plate_rotation: Matrix3<f64>,
    /// The shared model's noise-free reading of the plate: the pixel (u, v) of every marker
    /// corner (markers 0–3, OpenCV order each); `None` when the lens is not pinhole +
    /// Brown–Conrady (the model's `lens_distortion`), e.g. an equidistant fisheye.
    pub corners: Option<Vec<Vector2<f64>>>,
    /// The model's metric reading of each marker's centre (what a marker pose's translation
    /// reports: the camera frame, `camera_scale` applied), m.
    pub marker_points: Vec<Vector3<f64>>,
}

/// What a stationing program's point is for (the import layout's `role`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointRole {
    /// Fits the model (`/measured_points`).
    Fit,
    /// Kept out of every fit, to judge predictions (`/check_points`).
    Check,
}

/// A stationing program's reading of the tool point by the levelled instrument
/// ([`crate::stationing`]): one per waypoint, taken in the middle of its dwell.
#[derive(Debug, Clone, PartialEq)]
pub struct StationPointSample {
    pub t: f64,
    /// `G<group>.<index>` (1-based, e.g. `G03.017`).
    pub point_id: String,
    pub role: PointRole,
    /// The instrument's placement the point was measured from (`sensors.tracker.setups`).
    pub setup: Arc<str>,
    /// The point in the instrument's frame at that placement (m).
    pub measured: Vector3<f64>,
    /// Stated covariance of `measured` (m²): the point noise's σ² on the diagonal.
    pub covariance: Matrix3<f64>,
    /// The commanded tool point, nominal kinematics, in the arm's base frame (m).
    pub nominal: Vector3<f64>,
}

/// A 3-axis accelerometer's reading at a waypoint (the arm at rest).
#[derive(Debug, Clone, PartialEq)]
pub struct AccelerationSample {
    pub t: f64,
    pub sensor: Arc<str>,
    /// The URDF link whose frame the sensor reads in.
    pub link: Arc<str>,
    /// Specific force in the sensor's frame (m/s²): +9.81 along its up axis at rest, level.
    pub specific_force: Vector3<f64>,
    /// Stated variance of each axis (m²/s⁴): the noise's σ².
    pub variance: f64,
}

/// Everything a simulation streams, in time order.
#[derive(Debug, Clone, PartialEq)]
pub enum Sample {
    Tracker(TrackerSample),
    Temperature(TemperatureSample),
    MachineState(MachineStateSample),
    ProbeHit(ProbeHitSample),
    CameraFrameRequest(CameraFrameRequest),
    StationPoint(StationPointSample),
    Acceleration(AccelerationSample),
}

impl Sample {
    /// Time of the sample (s).
    pub fn t(&self) -> f64 {
        match self {
            Sample::Tracker(s) => s.t,
            Sample::Temperature(s) => s.t,
            Sample::MachineState(s) => s.t,
            Sample::ProbeHit(s) => s.t,
            Sample::CameraFrameRequest(s) => s.t,
            Sample::StationPoint(s) => s.t,
            Sample::Acceleration(s) => s.t,
        }
    }
}

/// Ground truth behind a tracker sample.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerTruth {
    /// Commanded axis positions (m) of a cartesian or delta machine; for five_axis and
    /// serial_arm the nominal tool point (forward kinematics of `joints`, workpiece/cell frame).
    pub commanded: Vector3<f64>,
    /// Commanded joint vector (the family's, see [`crate::families`]).
    pub joints: Vec<f64>,
    /// True machine displacement (tool relative to workpiece, machine frame): Σ true terms.
    pub displacement: Vector3<f64>,
    /// True tool (target) point, workpiece frame: the tool relative to the true part, what the
    /// tracker sights (crates/model `ToolState::target`).
    pub tool_point: Vector3<f64>,
    /// True target point in the tracker frame (no instrument error).
    pub point: Vector3<f64>,
    /// True range |point| (m).
    pub range: f64,
    pub warmup_range_error: f64,
    pub refraction_range_error: f64,
    /// Index of the air on the beam.
    pub true_index: f64,
    /// σ of the range noise actually applied (turbulence included).
    pub range_sigma: f64,
}

/// Ground truth paired with each sample by [`crate::Simulation::samples_with_truth`].
#[derive(Debug, Clone, PartialEq)]
pub enum SampleTruth {
    Tracker(TrackerTruth),
    /// True temperature at the sensor location (°C).
    Temperature {
        true_value: f64,
    },
    /// True displacement (machine frame, m).
    MachineState {
        displacement: Vector3<f64>,
    },
    /// True machine displacement and pretravel vector at the hit (m).
    ProbeHit {
        displacement: Vector3<f64>,
        pretravel: Vector3<f64>,
    },
    /// True tool point (workpiece frame; cell frame for an arm), the commanded joint vector
    /// of the dwell (the family's, see [`crate::families`]) and the true displacement d (as in
    /// [`TrackerTruth::displacement`]).
    CameraFrameRequest {
        tool_point: Vector3<f64>,
        joints: Vec<f64>,
        displacement: Vector3<f64>,
    },
    /// The true tool point in the arm's base frame and in the levelled frame (the ground's tilt
    /// applied), the true point in the instrument's frame (no noise), the commanded joints.
    StationPoint {
        tool_point: Vector3<f64>,
        levelled: Vector3<f64>,
        point: Vector3<f64>,
        joints: Vec<f64>,
    },
    /// The noise-free reading (misalignment and bias included) and the gravity in the base.
    Acceleration {
        specific_force: Vector3<f64>,
        gravity: Vector3<f64>,
    },
}

/// True value of one term parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueParameter {
    /// `label.param`, e.g. `thermal_scale[x].alpha`.
    pub name: String,
    pub value: f64,
    pub unit: &'static str,
}
