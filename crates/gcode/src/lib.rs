//! # metrocell-gcode — compensating a part program with a machine's error model
//!
//! A machine told to go to X reaches X + e(X), where e is its error field (the sum of its
//! geometric, thermal and load terms). Compensation in software rewrites the program so that
//! every commanded point C satisfies C + e(C) = T for the programmed target T, without touching
//! the controller (seed 000, §4.3 and Fig. 2).
//!
//! * [`error_field::ErrorField`] — what the compensator needs of a model: e at a commanded
//!   position and approach direction, and the region where the model was calibrated.
//!   [`planar_quadratic::PlanarQuadraticField`] is seed 000's eq. 7 (nine coefficients A–I);
//!   [`planar_field_fit`] identifies them from measured holes, with their covariance.
//! * [`model_field::ModelErrorField`] — a fitted model file's machine terms (the shared forward
//!   model) as an error field, at stated conditions (temperatures, load).
//! * [`controller_table`] — per-axis pitch/straightness/reversal tables and squareness sampled
//!   from a field, in a documented CSV layout a controller loads.
//! * [`inverse`] — solving C + e(C) = T by fixed-point iteration (or the paper's first-order
//!   C = T − e(T)).
//! * [`block`] — one G-code line split into words and comments, exactly as written.
//! * [`arc`] — G2/G3 arcs as chords within a tolerance.
//! * [`program`] — the whole program: modal state (G0–G3, G17–G19, G20/G21, G90/G91), the
//!   programmed and the commanded position, subdivision of straight moves where the field
//!   bends them, a report of what changed, warnings outside the calibrated region, and
//!   malformed lines passed through untouched with their line numbers.
//!
//! Conventions, stated once here: the error field works in SI (metres, machine axes X Y Z) and
//! is *reached − commanded*; programs are in their own units (G21 mm, G20 inch) and are
//! converted at the boundary. A line whose commanded position equals its programmed position
//! (to 1e-12 m) is written back byte for byte, so a zero model changes nothing but the header
//! comment.

pub mod arc;
pub mod block;
pub mod controller_table;
pub mod cutter_compensation;
pub mod error_field;
pub mod fdm_toolpath;
pub mod hole_plate_job;
pub mod inverse;
pub mod model_field;
pub mod number_format;
pub mod planar_field_fit;
pub mod planar_quadratic;
pub mod program;

pub use error_field::{ErrorField, FieldError, Region, ZeroField};
pub use inverse::{compensate_point, InverseMethod};
pub use model_field::{ModelErrorField, ModelFieldError};
pub use planar_quadratic::PlanarQuadraticField;
pub use program::{compensate_program, CompensationOptions, CompensationReport, LineIssue};
