//! Corrections applied to one measurement, as pure functions over plain numbers.
//!
//! The physics lives in `metrocell-physics`; this crate turns its catalog terms into what a node
//! does to one measured point. Used by a node today: the thermal corrections (`thermal_*`, by
//! `metrocell-thermal`): axis scales (`thermal_scale`), structure growth with a first-order lag
//! (`thermal_growth`), workpiece expansion about its clamp (`workpiece_expansion`), each
//! evaluated by the catalog term, with u(α), u(g), u(τ) and sensor variances propagated into the
//! point's covariance, and an online fit of a growth term's g and τ from a reference point.
//! Not yet used by any node (the tracker node is to use them): re-correcting a tracker range
//! for the air the instrument did not see (`tracker_correction`), propagating spherical noise
//! into a Cartesian covariance (`spherical`).
//! Units are SI throughout (m, rad, Pa, s, °C, relative humidity as a 0..1 fraction).

pub mod spherical;
pub mod thermal_compensator;
pub mod thermal_drift;
pub mod thermal_error;
pub mod thermal_growth_compensation;
pub mod thermal_growth_fit;
pub mod thermal_lag_filter;
pub mod thermal_scale_compensation;
pub mod thermal_signals;
pub mod thermal_workpiece_compensation;
pub mod tracker_correction;

pub use spherical::{spherical_to_cartesian, SphericalNoise};
pub use thermal_compensator::ThermalCompensator;
pub use thermal_error::{Reading, ThermalError};
pub use thermal_growth_compensation::{GrowthCompensator, GrowthSpec};
pub use thermal_growth_fit::{GrowthFit, GrowthFitResult};
pub use thermal_lag_filter::FirstOrderLag;
pub use thermal_scale_compensation::{AxisSensorPlacement, ThermalScaleCompensator};
pub use thermal_workpiece_compensation::WorkpieceCompensator;
pub use tracker_correction::{refraction_corrected_range, warmup_status, AirData};
