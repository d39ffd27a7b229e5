//! # metrocell-twin — the digital twin's simulation core
//!
//! A *cell description* (YAML, [`cell_file::CellFile`] → validated [`Cell`]) names the machine
//! (family, stacking order, travels), its sensors with poses and noise, the environment over the
//! shift (lumped thermal model, air), the measurement program and the machine's true error terms
//! (physics catalog [`metrocell_physics::TermConfig`]s). The same file with fewer terms is a
//! user's nominal model. A [`Simulation`] turns a cell, a duration and a seed into a
//! time-ordered *stream* of typed [`Sample`]s (flat memory), with the ground truth of each
//! sample available from [`Simulation::samples_with_truth`] and the true parameters from
//! [`Simulation::ground_truth`].
//!
//! Conventions (stated once, here):
//! * SI units everywhere (m, rad, s, Pa); temperatures °C, humidity %RH. Times are seconds
//!   from the start of the shift.
//! * Axis coordinates q follow ISO 841 / crates/kinematics: the commanded motion of the tool
//!   relative to the workpiece; the nominal tool point in the workpiece frame is q + tool_offset
//!   for every stacking order. The workpiece frame coincides with the machine frame at q = 0.
//!   Five-axis and serial-arm programs use joint vectors instead (`x y z b c`; the arm's joints),
//!   with the tool point from forward kinematics: see [`families`].
//! * Machine errors: displacement of the tool relative to the workpiece, realised − commanded,
//!   machine frame (physics crate convention); actual = commanded + Σ true terms.
//! * The laser tracker sits on the workpiece side (thesis set-up: on the X table) with pose
//!   `p_wp = R·p_LT + T`, `R = Rx(a)·Ry(b)·Rz(c)`; it reads `X_LT = Rᵀ(p_wp − T)` (thesis eq. 3.5).
//!   Spherical coordinates: see [`tracker_model`].
//! * Noise: every source has its own ChaCha8 stream derived from the seed ([`noise`]).
//! * A stationing program ([`stationing`]: an arm measured by a levelled instrument from
//!   several setups, fit and check waypoints, accelerometers, the ground tilted) streams one row
//!   of samples per waypoint instead of the periodic channels.

// `!(x > 0.0)` is used on purpose: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cell;
pub mod disturbance;
pub mod fiducial_plate;
pub mod following_error;
pub mod model_writer;
mod model_writer_instruments;
pub mod noise;
pub mod program;
pub mod sample;
pub mod simulation;
pub mod stationing;
pub mod stationing_program;
mod stationing_run;
pub mod thermal_stepper;
pub mod tracker_model;
pub mod yaml_edit;

/// The cell file format, its errors, the machine builders and the model loader live below the
/// twin, in crates/model_file (the loader every model user shares); re-exported here under
/// their old paths.
pub use metrocell_model_file::{cell_file, cell_model, error, families, quantity};
pub use metrocell_model_file::{CellError, CellModel};

pub use cell::{Cell, MachineGeometry, MachineKinematics};
pub use fiducial_plate::FiducialPlate;
pub use model_writer::{write_model, FittedParameter, ModelUpdate};
pub use sample::{
    AccelerationSample, CameraFrameRequest, MachineStateSample, PointRole, ProbeHitSample, Sample,
    SampleTruth, StationPointSample, TemperatureSample, TrackerSample, TrackerStatus, TrackerTruth,
    TrueParameter,
};
pub use simulation::{GroundTruth, SampleStream, SignalsStream, Simulation, TruthStream};
pub use stationing::{Stationing, STATION_FRAME};
