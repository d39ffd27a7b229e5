//! Kinematics of the digital twin's machine families: Cartesian 3-axis machines in any stacking order
//! (nominal and with the thesis error chain), the five-axis tilting/rotary-table machine, the linear delta
//! (Marlin conventions), serial arms from DH tables or URDF, and camera-to-tool frame alignment; rigid
//! registration (Kabsch and the covariance-weighted pose from point correspondences); plus the
//! Jacobians of forward kinematics w.r.t. geometric parameters that the estimator needs.
//!
//! # Conventions (stated once, apply everywhere)
//! - Units: SI in the whole API — metres and radians. Seed figures in mm/degrees are converted in the tests.
//! - Frames: right-handed. `Isometry3` values named `t_a_b` map coordinates of frame `b` into frame `a`.
//! - Rotations: active; a positive angle is counter-clockwise looking down the axis towards the origin
//!   (right-hand rule). Roll–pitch–yaw is the URDF convention `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
//! - Small-angle error matrices (thesis P5 eq. 6): `R(ε) = I + [ε]×`, with `ε = (εx, εy, εz)` the rotation
//!   about x, y, z of the moving carriage.
//! - Each module documents its own machine frame once, at the top.

pub mod axis_servo;
pub mod cartesian;
pub mod cartesian_error_chain;
pub mod delta;
pub mod delta_firmware;
pub mod delta_rod_correction;
pub mod dh;
pub mod error;
pub mod five_axis;
pub mod five_axis_dynamics;
pub mod frame_alignment;
pub mod frame_alignment_procedure;
pub mod gravity;
pub mod instrument_pose;
pub mod rigid_registration;
pub mod serial;
pub mod serial_ik;
pub mod transform;
pub mod urdf_chain;
pub mod urdf_link_placement;

pub use error::KinematicsError;
pub use instrument_pose::InstrumentPose;
pub use rigid_registration::{
    kabsch_rigid, kabsch_rotation, register, Correspondence, Registration, RegistrationError,
};
