//! Corrections the nodes apply online, as pure functions over plain numbers.
//!
//! The physics lives in `metrocell-physics`; this crate turns it into what a node does to one
//! measurement: re-correct a tracker range for the air the instrument did not see, propagate
//! spherical noise into a Cartesian covariance, remove the thermal growth of the axis scales.
//! Units are SI throughout (m, rad, Pa, °C, relative humidity as a 0..1 fraction).

pub mod spherical;
pub mod thermal_scale_compensation;
pub mod tracker_correction;

pub use spherical::{cartesian_to_spherical, spherical_to_cartesian, SphericalNoise};
pub use thermal_scale_compensation::{AxisSensorPlacement, ThermalScaleCompensator, ThermalError};
pub use tracker_correction::{range_for_index, refraction_corrected_range, warmup_status, AirData};
