//! Laser-tracker spherical coordinates to Cartesian, with the covariance that follows: the
//! physics crate holds the one implementation ([`metrocell_physics::instrument::spherical`]);
//! the nodes import it from here.

pub use metrocell_physics::instrument::spherical::{
    from_spherical, point_covariance, spherical_jacobian, spherical_to_cartesian, to_spherical,
    SphericalNoise,
};
