//! metrocell-vision: fiducial measurement for metrocell (pure Rust, no DDS).
//!
//! Pixel convention (everywhere in this crate, as OpenCV): pixel (i, j) covers the unit square
//! centred at (x = i, y = j); the centre of the top-left pixel is (0, 0), x to the right, y down.

pub mod aruco;
pub mod bar_lengths;
pub mod camera;
pub mod checkerboard;
pub mod contour;
pub mod edge_fit;
pub mod edge_profile;
pub mod error;
pub mod filters;
pub mod hole_grid;
pub mod hole_plate;
pub mod holes;
pub mod marker_pose;
pub mod polygon;
pub mod printed_star;
pub mod printed_star_solid;
pub mod render;
pub mod saddle_fit;
pub mod scale;
pub mod targets;
pub mod threshold;

pub use camera::{CameraModel, Distortion};
pub use error::{Result, VisionError};
pub use render::{
    render_view, MarkerTruth, PlanarTarget, RenderSettings, RenderedView, TargetItem,
};
pub use targets::{
    detect_targets, detect_targets_explained, Detection, PoseInputs, Target, TargetFamily,
    TargetPose,
};
