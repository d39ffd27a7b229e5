//! # metrocell-model-file — a cell file read as the model
//!
//! One loader turns a cell file (YAML, [`cell_file::CellFile`]) into what the shared forward
//! model (crates/model) is made of: the machine ([`machine_section`]), its declared error terms
//! ([`terms_section`]) and its instruments' terms, by the one rule of [`instrument_terms`].
//! [`CellModel`] owns them and lends a [`metrocell_model::ForwardModel`]. `metrocell
//! calibrate`, `diagnose`, `compensate`, the estimator and diagnose nodes load their model here;
//! crates/twin builds the machine and the true terms of a cell it simulates with the same
//! functions and adds the simulator's truth, noise and schedule. No DDS, no simulation.

pub mod cell_file;
pub mod cell_model;
pub mod error;
pub mod families;
pub mod instrument_terms;
pub mod machine_section;
pub mod quantity;
pub mod terms_section;

pub use cell_model::{CellModel, DEFAULT_TILT_SIGMA};
pub use error::CellError;
pub use instrument_terms::{instrument_terms, InstrumentTerms};
