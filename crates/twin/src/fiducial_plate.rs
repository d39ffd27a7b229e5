//! The fiducial plate the twin's camera sees at each dwell: crates/model `fiducial_plate` (the
//! plate's layout and placement are shared with the renderer and with measurement records).

pub use metrocell_model::fiducial_plate::*;
