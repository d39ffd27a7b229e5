//! Volumetric error synthesis of a Cartesian XFYZ machine from its 21 geometric errors
//! (thesis P5 = Sensors 2019 eqs (2), (6)–(9); digest 001 part 1 §3.3 "version B").
//!
//! Chain (X carries the workpiece, Y and Z carry the tool; tracker pose omitted, i.e.
//! R_LT = I, T_LT = 0; thermal terms omitted — they are separate catalog terms):
//!
//! ```text
//! P = R_X⁻¹ · ( R_Y · ( R_Z · T + Z ) + Y − X )                      (P5 eq. 2)
//! R(k) = [[1, −εz(k), εy(k)], [εz(k), 1, −εx(k)], [−εy(k), εx(k), 1]] = I + [ε(k)]×   (eq. 6)
//! X = (−x + δx(x), δy(x), δz(x))                                       (eq. 7)
//! Y = (δx(y) − y·s_xy, y + δy(y), δz(y))                               (eq. 8)
//! Z = (δx(z) − z·s_xz, δy(z) − z·s_yz, z + δz(z))                      (eq. 9)
//! ```
//! P is the tool point T (tool offset, m) expressed in the workpiece (table) frame; with all
//! errors zero P₀ = T + (x, y, z). The volumetric error is E = P − P₀. The exact chain (any
//! stacking order, R(k) inverted exactly) is crates/kinematics `cartesian_error_chain`, the
//! project's one copy of the chain; this file is the test oracle only: P5's first-order
//! synthesis written out as the paper gives it, which the catalog terms must sum to and which
//! the exact chain must match to second order (tests/volumetric.rs).
//!
//! Sign conventions (exactly P5's): δ(k) and ε(k) are the error motions of axis k's carriage.
//! X is on the workpiece side, so its errors enter the tool-relative-to-workpiece error with a
//! minus sign. First order (products of errors dropped), as [`xfyz_volumetric_error_first_order`]
//! implements:
//!
//! ```text
//! E ≈ δ(y) + δ(z) − δ(x) − (y·s_xy + z·s_xz, z·s_yz, 0)
//!     + ε(z) × T + ε(y) × (T + z·e_z) − ε(x) × (T + x·e_x + y·e_y + z·e_z)
//! ```
//! The catalog's geometric terms use the tool-relative-to-workpiece convention, so the same E is
//! the sum of: positioning/straightness of Y, Z with δ as is and of X with −δ(x); angular of Z
//! (`lever_axes: []`, `abbe_offset: T`), of Y (`lever_axes: [z]`, abbe T) and of X with −ε(x)
//! (`lever_axes: [x, y, z]`, abbe T); squareness pairs xy, xz, yz. The crate tests check this.

use nalgebra::Vector3;

use metrocell_physics::geometry::error_series::ErrorSeries;
use metrocell_physics::{Axis, PhysicsError};

/// Values of the six error motions of one axis at one position.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisErrorValues {
    /// (δx, δy, δz)(q): one positioning and two straightness errors, m.
    pub translation: Vector3<f64>,
    /// (εx, εy, εz)(q): roll/pitch/yaw about machine X, Y, Z, rad.
    pub rotation: Vector3<f64>,
}

/// The three squareness errors s_xy, s_xz, s_yz (rad), P5 sign convention.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SquarenessValues {
    pub xy: f64,
    pub xz: f64,
    pub yz: f64,
}

/// The 21 errors as series over the travels: for each axis, 3 translation and 3 rotation
/// series (with their coefficients), plus the 3 squarenesses.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometricErrorModel {
    /// `[axis][component]` → (series shape, coefficients). Translations in m.
    pub translation: [[(ErrorSeries, Vec<f64>); 3]; 3],
    /// `[axis][component]` → (series shape, coefficients). Rotations in rad.
    pub rotation: [[(ErrorSeries, Vec<f64>); 3]; 3],
    pub squareness: SquarenessValues,
}

impl GeometricErrorModel {
    /// All 21 errors zero, every series with the given shape (e.g. one per axis travel).
    pub fn zeros(series: [ErrorSeries; 3]) -> Self {
        let comp = |a: usize| std::array::from_fn(|_| (series[a], vec![0.0; series[a].len()]));
        Self {
            translation: std::array::from_fn(comp),
            rotation: std::array::from_fn(comp),
            squareness: SquarenessValues::default(),
        }
    }

    /// Evaluate the six error motions of `axis` at position q.
    pub fn axis_errors(&self, axis: Axis, q: f64) -> AxisErrorValues {
        let a = axis.index();
        let mut v = AxisErrorValues::default();
        for c in 0..3 {
            let (s, k) = &self.translation[a][c];
            v.translation[c] = s.eval(k, q);
            let (s, k) = &self.rotation[a][c];
            v.rotation[c] = s.eval(k, q);
        }
        v
    }

    /// Check every coefficient vector has the length its series needs.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        for a in Axis::ALL {
            for c in 0..3 {
                for (kind, (s, k)) in [
                    ("translation", &self.translation[a.index()][c]),
                    ("rotation", &self.rotation[a.index()][c]),
                ] {
                    if k.len() != s.len() {
                        return Err(PhysicsError::InvalidInput {
                            what: format!("geometric error model, axis {a}, {kind} component {c}"),
                            reason: format!(
                                "series of order {} needs {} coefficients, got {}",
                                s.order,
                                s.len(),
                                k.len()
                            ),
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

/// First-order volumetric error E = P − (T + q) of the XFYZ chain (see the module docs).
pub fn xfyz_volumetric_error_first_order(
    q: &Vector3<f64>,
    tool: &Vector3<f64>,
    errors: &dyn Fn(Axis, f64) -> AxisErrorValues,
    sq: &SquarenessValues,
) -> Vector3<f64> {
    let ex = errors(Axis::X, q.x);
    let ey = errors(Axis::Y, q.y);
    let ez = errors(Axis::Z, q.z);
    ey.translation + ez.translation
        - ex.translation
        - Vector3::new(q.y * sq.xy + q.z * sq.xz, q.z * sq.yz, 0.0)
        + ez.rotation.cross(tool)
        + ey.rotation.cross(&(tool + Vector3::new(0.0, 0.0, q.z)))
        - ex.rotation.cross(&(tool + q))
}
