//! The pure parts of the `metrocell-fiducial` node (no DDS), unit-tested here:
//! - [`frame`]: sensor_msgs/Image → 8-bit grey image, with a per-frame error naming the problem;
//! - [`detection_msgs`]: detected targets → FiducialDetectionArray and PoseWithCovarianceStamped;
//! - [`processing`]: parameters and the per-message work shared by the live run and the bag replay.

pub mod detection_msgs;
pub mod frame;
pub mod processing;
