//! ArUco square fiducials: dictionaries, marker images, detection.

pub mod detect;
pub mod dictionary;
mod dictionary_data;
pub mod marker_image;

pub use detect::{detect_markers, DetectedMarker, DetectorParams};
pub use dictionary::{Dictionary, Identification};
pub use marker_image::generate_marker_image;
