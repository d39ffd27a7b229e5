//! The one pose type of an instrument: defined in crates/kinematics (`instrument_pose`, with its
//! frame convention), below the model and the exact error chain that both use it.

pub use metrocell_kinematics::instrument_pose::InstrumentPose;
