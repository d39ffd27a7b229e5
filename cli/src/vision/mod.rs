//! `metrocell detect` and `metrocell camera ...`: the vision library on image files.

pub mod camera_command;
pub mod detect;
pub mod image_input;
pub mod photo_source;
pub mod simulated_photos;
