//! The topic names of a metrocell cell: one list for the twin that publishes them, `bag import`
//! that writes them from CSV, and the records builder that reads them. A node may remap any of
//! them (`--ros-args -r`), but these are the names a recording has unless someone chose others.

pub const CLOCK: &str = "/clock";
/// Actual axis positions (what the encoders report).
pub const JOINT_STATES: &str = "/machine/joint_states";
/// Commanded axis positions and velocities (`sensor_msgs/JointState`).
pub const COMMANDED_JOINTS: &str = "/machine/commanded_joint_states";
/// Recorded approach directions: `name` = axes, `position` = ±1 (`sensor_msgs/JointState`).
pub const APPROACH: &str = "/machine/approach_directions";
/// Load force on the machine (`geometry_msgs/WrenchStamped`, machine frame).
pub const LOAD: &str = "/machine/load";
/// The active tool's (a target's, e.g. a tracker reflector on the spindle) offset from the
/// spindle's gauge point, machine frame, m (`geometry_msgs/PointStamped`): published when the
/// tool or target changes, so a verification with reflectors at several offsets is one recording.
pub const TOOL_OFFSET: &str = "/machine/tool_offset";
/// When the instrument was powered on (`sensor_msgs/TimeReference`, `time_ref`).
pub const POWER_ON: &str = "/tracker/power_on";
/// Per-sensor temperatures: `/temperature/<sensor name>` (`sensor_msgs/Temperature`).
pub const TEMPERATURE_PREFIX: &str = "/temperature/";
/// Raw tracker readings (`metrocell_msgs/TrackerMeasurement`).
pub const TRACKER_MEASUREMENTS: &str = "/tracker/measurements";
/// Touch-probe hits (`metrocell_msgs/ProbeHit`).
pub const PROBE_HITS: &str = "/probe/hits";
pub const CAMERA_INFO: &str = "/camera/camera_info";
pub const CAMERA_IMAGE: &str = "/camera/image_raw";
/// The fiducial node's detections of each frame (`metrocell_msgs/FiducialDetectionArray`); it
/// publishes them on `fiducials` in its namespace, this name at the root.
pub const FIDUCIALS: &str = "/fiducials";
/// Measured points (`metrocell_msgs/MeasuredPoint`) that fit a model.
pub const MEASURED_POINTS: &str = "/measured_points";
/// Check points (`metrocell_msgs/MeasuredPoint`): kept out of every fit, to judge predictions.
pub const CHECK_POINTS: &str = "/check_points";
/// Reference nests' readings (`metrocell_msgs/MeasuredPoint`): points the machine does not move.
pub const REFERENCE_POINTS: &str = "/reference_points";
/// Accelerometers: `/imu/<sensor>` (`sensor_msgs/Imu`, the specific force in the sensor's frame).
pub const IMU_PREFIX: &str = "/imu/";
/// Separates an instrument's frame and its setup (placement) in a point's `header.frame_id`:
/// `total_station@S1`.
pub const SETUP_SEPARATOR: char = '@';
