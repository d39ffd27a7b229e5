//! Corrections of single measurements, as pure functions over plain numbers.
//!
//! The physics lives in `metrocell-physics`; this crate turns it into what is done to one
//! measurement: remove the thermal growth of the axis scales (`ThermalScaleCompensator`, used by
//! the thermal node, nodes/thermal), re-correct a tracker range for the air the instrument did
//! not see and report its warm-up (`refraction_corrected_range`, `warmup_status`), and propagate
//! spherical noise into a Cartesian covariance (`spherical_to_cartesian`). The tracker functions
//! are used by no node yet (there is no tracker node); they are tested here only.
//! Units are SI throughout (m, rad, Pa, °C, relative humidity as a 0..1 fraction).

pub mod spherical;
pub mod thermal_scale_compensation;
pub mod tracker_correction;

pub use spherical::{spherical_to_cartesian, SphericalNoise};
pub use thermal_scale_compensation::{AxisSensorPlacement, ThermalScaleCompensator, ThermalError};
pub use tracker_correction::{refraction_corrected_range, warmup_status, AirData};
