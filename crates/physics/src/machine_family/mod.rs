//! Machine-family terms whose effect needs a kinematic chain (delta printers, serial arms).
pub mod kinematic_parameters;
pub use kinematic_parameters::{predict_through_kinematics, KinematicParameters};
