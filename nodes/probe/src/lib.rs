//! The pure part of the `metrocell-probe` node:
//! - [`compensation`]: a touch-trigger event (axis positions latched at the trigger, approach
//!   direction) → compensated surface point with covariance;
//! - [`processing`]: parameters and the per-message work shared by the live run and the bag replay.

pub mod compensation;
pub mod processing;
