//! Geometric errors of machine axes (ISO 230-1 / VDI 2617-3), rotary-axis location errors and frame misalignment.
pub mod angular;
pub mod backlash;
pub mod error_series;
pub mod frame_misalignment;
pub mod pitch_cyclic;
pub mod positioning;
pub mod rotary_axis_location;
pub mod squareness;
pub mod straightness;
