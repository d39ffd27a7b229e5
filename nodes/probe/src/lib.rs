//! The pure part of the `metrocell-probe` node: a touch-trigger event (axis positions latched at
//! the trigger, approach direction) → compensated surface point with covariance.

pub mod compensation;
