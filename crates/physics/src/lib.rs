//! # metrocell-physics — the physics-term catalog of the digital twin
//!
//! One catalog, used three ways: the simulator evaluates *true* terms, the estimator fits the
//! terms a model *declares*, and `diagnose` tries *candidate* terms the model lacks.
//!
//! * [`term::PhysicsTerm`] — a term: stable [`term_id::TermId`], documented equation, parameter
//!   descriptors ([`term::ParamSpec`], SI unit, plausible range, default), declared signals
//!   ([`signals::SignalKind`]), `predict` → [`term::Prediction`] (kind from
//!   [`term::EffectKind`]: displacement in a stated frame, range change, range scatter, image
//!   shift, point in frame, or kinematic), and an analytic `jacobian` w.r.t. its parameters.
//! * [`catalog`] — ids, docs, [`catalog::configure`] (serde config → validated term + params);
//!   [`model::TermModel`] — several terms with stacked parameters, summed displacement and
//!   Jacobian (a declared model, or declared + a `diagnose` candidate).
//! * [`geometry`] — the 21 ISO 230-1 errors as series over the travel, squareness, pitch-cyclic,
//!   backlash and frame misalignment (their sum is the XFYZ volumetric error; the exact chain is
//!   `metrocell_kinematics::cartesian_error_chain`).
//! * [`thermal`] — axis scale, structure growth (with first-order lag), workpiece expansion, and
//!   the lumped shift model ([`thermal::shift_model`]), CTE uncertainty (ISO/TR 230-9).
//! * [`instrument`] — Edlén (shop-floor, Birch & Downs, Bönsch & Potulski), refraction,
//!   tracker warm-up, turbulence, tracker pose, probe pretravel, lens distortion, camera scale,
//!   time offset, tracker range uncertainty budget.
//! * [`gravity`] — a serial robot under its own weight: joint compliance, joint backlash, a
//!   telescoping column's bending, its links' thermal expansion (kinematic terms).
//! * [`load`] — compliance, tool offset. [`machine_family`] — kinematic terms (delta, serial
//!   arms) evaluated through a forward-kinematics closure from crates/kinematics.
//!
//! Conventions: SI units everywhere (temperatures °C, humidity %RH). Machine-frame
//! displacements are the tool point relative to the workpiece, realised minus commanded.

// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod catalog;
pub mod config;
pub mod error;
pub mod geometry;
pub mod gravity;
pub mod instrument;
pub mod load;
pub mod machine_family;
pub mod model;
pub mod signals;
pub mod temperature_timeline;
pub mod term;
pub mod term_id;
pub mod thermal;
pub mod units;

pub use catalog::{configure, configure_described, entries, lookup, CatalogEntry, ConfiguredTerm};
pub use config::{ConfigValue, EstimationConfig, PriorConfig, TermConfig};
pub use error::PhysicsError;
pub use signals::{Axis, RotaryAxis, SignalKind, Signals};
pub use temperature_timeline::{TemperatureHistory, TemperatureTimeline};
pub use term::{EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction, Range};
pub use term_id::{Category, TermId};
