//! Corrections applied to one measurement, as pure functions over plain numbers.
//!
//! The physics lives in `metrocell-physics`; this crate turns its catalog terms into what a node
//! does to one measured point. Used by a node today: the thermal corrections (`thermal_*`, by
//! `metrocell-thermal`): axis scales (`thermal_scale`), structure growth with a first-order lag
//! (`thermal_growth`), workpiece expansion about its clamp (`workpiece_expansion`), each
//! evaluated by the catalog term, with u(α), u(g), u(τ) and sensor variances propagated into the
//! point's covariance, an online fit of a growth term's g and τ from a reference point
//! (`thermal_growth_fit`), and an online fit of the axis scales' α from reference points on an
//! axis (`thermal_scale_fit`).
//! Used by `metrocell-tracker`: re-correcting a tracker range for the air the instrument did not
//! see (`tracker_correction`), and spherical ↔ Cartesian with the covariance that follows
//! (`spherical`, re-exported from `metrocell_physics::instrument::spherical`).
//! Units are SI throughout (m, rad, Pa, s, °C, relative humidity as a 0..1 fraction).

pub mod spherical;
pub mod thermal_compensator;
pub mod thermal_drift;
pub mod thermal_error;
pub mod thermal_growth_compensation;
pub mod thermal_growth_fit;
pub mod thermal_scale_compensation;
pub mod thermal_scale_fit;
pub mod thermal_signals;
pub mod thermal_workpiece_compensation;
pub mod tracker_correction;

/// The one first-order lag filter of the workspace (crates/physics).
pub use metrocell_physics::thermal::first_order_lag::FirstOrderLag;
pub use spherical::{spherical_to_cartesian, to_spherical, SphericalNoise};
pub use thermal_compensator::ThermalCompensator;
pub use thermal_error::{Reading, ThermalError};
pub use thermal_growth_compensation::{GrowthCompensator, GrowthSpec};
pub use thermal_growth_fit::{GrowthFit, GrowthFitResult};
pub use thermal_scale_compensation::{AxisSensorPlacement, ThermalScaleCompensator};
pub use thermal_scale_fit::{ScaleFit, ScaleFitResult};
pub use thermal_workpiece_compensation::WorkpieceCompensator;
pub use tracker_correction::{range_for_index, refraction_corrected_range, warmup_status, AirData};
