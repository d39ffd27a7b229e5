//! # metrocell-model — the shared forward model
//!
//! One model, three users: the twin (crates/twin) evaluates it at the true parameters and adds
//! noise, scheduling and rendering; the estimator fits its parameters; `diagnose` adds candidate
//! terms to it. No DDS, no I/O.
//!
//! * [`machine`] — the machine families' validated geometry ([`MachineGeometry`],
//!   [`MachineKinematics`], [`FiveAxisMachine`], [`SerialArm`]) and the joint-vector conventions.
//! * [`instrument_pose`] — the one instrument pose type and its frame convention.
//! * [`forward`] — [`ForwardModel`]: the stacked parameter vector, the tool state (machine,
//!   tool- and workpiece-frame terms, kinematic terms) and its analytic Jacobian.
//! * [`instruments`] — the instrument terms grouped by instrument (two trackers or two cameras
//!   are told apart by instance name), camera geometry.
//! * [`tracker`], [`probe`], [`camera`] — each instrument's predicted reading and its analytic
//!   Jacobian w.r.t. every stacked parameter; [`workspace`] — their scratch buffers;
//!   [`linear_target`] — the sighted point kept per reading where the machine is linear in its
//!   parameters (a batch fit's evaluations become products);
//!   [`fiducial_plate`] — the plate of markers a simulated camera sees.
//! * [`parameters`] — free/fixed mask and priors per parameter ([`ParameterSetup`]), and the
//!   pairs of parameters parallel by construction ([`ForwardModel::parallel_pairs`]).
//! * [`signals_builder`] — [`SignalsBuilder`]: recorded streams (commanded joints, temperatures,
//!   air, power-on, load) → `Signals` at any instant, offline or streaming; with
//!   [`approach_rule`] (approach direction from the commanded trajectory) and
//!   [`sampled_series`] (interpolation and states on integer-ns times).
//!
//! Units SI (m, rad, s, Pa), temperatures °C, as in crates/physics.

// `!(x > 0.0)` is used on purpose: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod approach_rule;
mod arm_gravity;
pub mod camera;
pub mod fiducial_plate;
pub mod forward;
pub mod instrument_pose;
pub mod instruments;
pub mod linear_target;
pub mod machine;
pub mod parameters;
pub mod probe;
pub mod sampled_series;
pub mod signals_builder;
pub mod tracker;
pub mod workspace;

pub use camera::{CameraPrediction, CAMERA_ROWS};
pub use fiducial_plate::{FiducialPlate, PLATE_MARKERS};
pub use forward::{DisplacementCache, ForwardModel, KinematicTruth, ToolState};
pub use instrument_pose::InstrumentPose;
pub use instruments::{CameraGeometry, Instrument, InstrumentKind};
pub use linear_target::KeptLayout;
pub use machine::{
    ArmAccelerometer, FiveAxisMachine, MachineGeometry, MachineKinematics, SerialArm,
    FIVE_AXIS_JOINTS,
};
pub use parameters::{ParallelPair, ParameterSetup, Prior};
pub use probe::{ProbePrediction, ProbeTarget, PROBE_ROWS};
pub use signals_builder::{JointMotion, SignalsBuilder, SignalsBuilderOptions};
pub use tracker::{TrackerPrediction, TRACKER_ROWS};
pub use workspace::Workspace;
