//! Error chains of a Cartesian 3-axis machine with a laser tracker on the workpiece side (thesis digest 001).
//!
//! **Version B** (thesis eq. 3.5 = P4 eq. 8 = P5 eq. 2, written for `XFYZ` with the tracker on the X table):
//! `X_LT = R_LT⁻¹ · [ R_X⁻¹ · ( R_Y · ( R_Z · T + Z ) + Y − X ) − T_LT ]`.
//! Generalised here to any stacking order: tool side, from the bed outwards,
//! `p_bed = D_a1 + R_a1 (D_a2 + R_a2 (… + R_an T))`; workpiece side, from the bed outwards,
//! `p_wp = R_bm⁻¹ (… R_b1⁻¹ (p_bed − D_b1) … − D_bm)`; tracker: `X_LT = R_LT⁻¹ (p_wp − T_LT)`.
//! Per-axis translation `D_k = s_k q_k u_k + δ(k)` with `s_k` the carriage sign (−1 workpiece side, ISO 841),
//! `δ(k) = (δx(k), δy(k), δz(k))` positioning/straightness values at the current position, and the squareness-
//! tilted axis directions `u_X = (1,0,0)`, `u_Y = (−s_xy, 1, 0)`, `u_Z = (−s_xz, −s_yz, 1)` (P5 eqs 7–9: the
//! `XFYZ` case gives exactly `X = (−x + δx(x), δy(x), δz(x))`, `Y = (δx(y) − y s_xy, y + δy(y), δz(y))`,
//! `Z = (δx(z) − z s_xz, δy(z) − z s_yz, z + δz(z))`). Rotation errors: `R_k = I + [ε(k)]×` (P5 eq. 6), inverted
//! exactly. Thermal scale (P5 eq. 7 `x·α_x·(T − 20)`) enters the caller's positioning value `δk(k)`.
//! Tracker pose: `p_wp = R_LT · p_LT + T_LT` (tracker frame → workpiece/table frame), the project's one
//! [`InstrumentPose`].
//!
//! **Version A** (thesis Ch. 2 eqs 2.1–2.7, `XFYZ`, workpiece frame):
//! `W = R(X)(−X + Y) + R(X)R⁻¹(Y) Z + R(X)R⁻¹(Y)R⁻¹(Z) T`, `X = (x + xTx, xTy, xTz)`,
//! `Y = (yTx + xWy·y, y + yTy, yTz)` (the printed `xWz·y` corrected to `xWy·y`, digest §3.2),
//! `Z = (zTx + xWz·z, zTy + yWz·z, z + zTz)`, `R(k) = I − [ε(k)]×` (eq. 2.5, the transpose of P5's).
//! Version A's x has the opposite sign (tool moves −x relative to the part). With `x_A = −x`, equal translation
//! and rotation error values, and `W = −s`, the two versions agree to first order in the errors
//! (they differ by `R_A(k) − R_B(k)⁻¹ = O(ε²)`), as the digest's consistency check states.

use crate::cartesian::{LinearAxis, StackingOrder};
use crate::error::{check_finite, KinematicsError};
use crate::instrument_pose::InstrumentPose;
use crate::transform::skew;
use metrocell_solver::numeric_jacobian::{central_difference, Order};
use nalgebra::{Matrix3, Vector3};

/// Error values of one axis at its current position (metres, radians).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisErrors {
    /// `(δx(k), δy(k), δz(k))`: positioning along the axis's own direction, straightness across it.
    pub translation: Vector3<f64>,
    /// `(εx(k), εy(k), εz(k))`: small rotations of the carriage about x, y, z.
    pub rotation: Vector3<f64>,
}

/// Squareness errors (P5 notation), radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Squareness {
    pub xy: f64,
    pub xz: f64,
    pub yz: f64,
}

/// All error values of a 3-axis machine at one position.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MachineErrors {
    /// Indexed by [`LinearAxis::index`].
    pub axes: [AxisErrors; 3],
    pub squareness: Squareness,
}

/// Small-angle rotation error matrix of P5 eq. 6: `I + [ε]×`.
pub fn small_angle_matrix(eps: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::identity() + skew(eps)
}

fn invert(m: &Matrix3<f64>, what: &str) -> Result<Matrix3<f64>, KinematicsError> {
    m.try_inverse()
        .ok_or_else(|| KinematicsError::InvalidValue {
            field: what.to_string(),
            value: m.determinant(),
            reason: "matrix is singular".into(),
        })
}

fn check_vec(field: &str, v: &Vector3<f64>) -> Result<(), KinematicsError> {
    for (i, c) in v.iter().enumerate() {
        check_finite(&format!("{field}[{i}]"), *c)?;
    }
    Ok(())
}

/// Translation vector `D_k` of axis `axis` (version B, generalised), for axis coordinate `q`.
pub fn axis_translation(
    order: &StackingOrder,
    axis: LinearAxis,
    q: f64,
    errors: &MachineErrors,
) -> Vector3<f64> {
    let s = &errors.squareness;
    let u = match axis {
        LinearAxis::X => Vector3::new(1.0, 0.0, 0.0),
        LinearAxis::Y => Vector3::new(-s.xy, 1.0, 0.0),
        LinearAxis::Z => Vector3::new(-s.xz, -s.yz, 1.0),
    };
    u * (order.carriage_sign(axis) * q) + errors.axes[axis.index()].translation
}

/// Version B: tool tip in the workpiece frame for axis coordinates `q`, tool offset `tool` and errors.
pub fn workpiece_point(
    order: &StackingOrder,
    q: &Vector3<f64>,
    tool: &Vector3<f64>,
    errors: &MachineErrors,
) -> Result<Vector3<f64>, KinematicsError> {
    check_vec("q", q)?;
    check_vec("tool offset", tool)?;
    for (k, a) in errors.axes.iter().enumerate() {
        check_vec(&format!("axis {k} translation error"), &a.translation)?;
        check_vec(&format!("axis {k} rotation error"), &a.rotation)?;
    }
    for (n, v) in [
        ("s_xy", errors.squareness.xy),
        ("s_xz", errors.squareness.xz),
        ("s_yz", errors.squareness.yz),
    ] {
        check_finite(n, v)?;
    }
    let mut p = *tool;
    for &axis in order.tool_side.iter().rev() {
        let r = small_angle_matrix(&errors.axes[axis.index()].rotation);
        p = axis_translation(order, axis, q[axis.index()], errors) + r * p;
    }
    for &axis in order.workpiece_side.iter() {
        let r = small_angle_matrix(&errors.axes[axis.index()].rotation);
        p = invert(&r, "workpiece-side rotation error matrix")?
            * (p - axis_translation(order, axis, q[axis.index()], errors));
    }
    Ok(p)
}

/// Version B with the tracker: the point as the tracker on the workpiece side measures it (`X_LT`).
pub fn tracker_point(
    order: &StackingOrder,
    q: &Vector3<f64>,
    tool: &Vector3<f64>,
    errors: &MachineErrors,
    tracker: &InstrumentPose,
) -> Result<Vector3<f64>, KinematicsError> {
    let p = workpiece_point(order, q, tool, errors)?;
    Ok(invert(&tracker.rotation, "tracker rotation")? * (p - tracker.translation))
}

/// Error values in the notation of thesis Ch. 2 (VDI 2617-3, Table 2.1) for version A.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VersionAErrors {
    /// `(kTx, kTy, kTz)` and `(kRx, kRy, kRz)` per axis, indexed by [`LinearAxis::index`].
    pub axes: [AxisErrors; 3],
    /// xWy, xWz, yWz.
    pub x_w_y: f64,
    pub x_w_z: f64,
    pub y_w_z: f64,
}

/// Version A (thesis eq. 2.1, `XFYZ` only): `W` for version-A coordinates `(x_A, y, z)`.
pub fn version_a_xfyz(
    q_a: &Vector3<f64>,
    tool: &Vector3<f64>,
    e: &VersionAErrors,
) -> Result<Vector3<f64>, KinematicsError> {
    check_vec("q", q_a)?;
    check_vec("tool offset", tool)?;
    let (x, y, z) = (q_a.x, q_a.y, q_a.z);
    let t = |k: usize| e.axes[k].translation;
    let r = |k: usize| Matrix3::identity() - skew(&e.axes[k].rotation);
    let xv = Vector3::new(x, 0.0, 0.0) + t(0);
    let yv = Vector3::new(e.x_w_y * y, y, 0.0) + t(1);
    let zv = Vector3::new(e.x_w_z * z, e.y_w_z * z, z) + t(2);
    let rx = r(0);
    let ry_inv = invert(&r(1), "R(Y)")?;
    let rz_inv = invert(&r(2), "R(Z)")?;
    Ok(rx * (-xv + yv) + rx * ry_inv * zv + rx * ry_inv * rz_inv * tool)
}

/// Maps version-B errors to the version-A values that describe the same machine to first order
/// (translations and rotations equal, `W = −s`), per the digest's consistency check.
pub fn version_a_errors_from_b(e: &MachineErrors) -> VersionAErrors {
    VersionAErrors {
        axes: e.axes,
        x_w_y: -e.squareness.xy,
        x_w_z: -e.squareness.xz,
        y_w_z: -e.squareness.yz,
    }
}

/// Names of the 21 geometric error values in [`MachineErrors::to_vector`] order: per axis X, Y, Z the
/// translations `δx(k), δy(k), δz(k)` then rotations `εx(k), εy(k), εz(k)`; then `s_xy, s_xz, s_yz`.
pub const MACHINE_ERROR_NAMES: [&str; 21] = [
    "delta_x(x)",
    "delta_y(x)",
    "delta_z(x)",
    "eps_x(x)",
    "eps_y(x)",
    "eps_z(x)",
    "delta_x(y)",
    "delta_y(y)",
    "delta_z(y)",
    "eps_x(y)",
    "eps_y(y)",
    "eps_z(y)",
    "delta_x(z)",
    "delta_y(z)",
    "delta_z(z)",
    "eps_x(z)",
    "eps_y(z)",
    "eps_z(z)",
    "s_xy",
    "s_xz",
    "s_yz",
];

impl MachineErrors {
    /// The 21 values in [`MACHINE_ERROR_NAMES`] order.
    pub fn to_vector(&self) -> nalgebra::SVector<f64, 21> {
        let mut v = nalgebra::SVector::<f64, 21>::zeros();
        for k in 0..3 {
            v.fixed_rows_mut::<3>(6 * k)
                .copy_from(&self.axes[k].translation);
            v.fixed_rows_mut::<3>(6 * k + 3)
                .copy_from(&self.axes[k].rotation);
        }
        v[18] = self.squareness.xy;
        v[19] = self.squareness.xz;
        v[20] = self.squareness.yz;
        v
    }

    /// Inverse of [`Self::to_vector`].
    pub fn from_vector(v: &nalgebra::SVector<f64, 21>) -> Self {
        let mut e = Self::default();
        for k in 0..3 {
            e.axes[k].translation = v.fixed_rows::<3>(6 * k).into_owned();
            e.axes[k].rotation = v.fixed_rows::<3>(6 * k + 3).into_owned();
        }
        e.squareness = Squareness {
            xy: v[18],
            xz: v[19],
            yz: v[20],
        };
        e
    }
}

/// Jacobian (3 × 21) of the tracker-frame point (version B) w.r.t. the 21 error values, by central differences
/// with an absolute step of 1e-7 (m or rad). The chain is bilinear-to-rational in the errors with second
/// derivatives of the order of the machine's lever arms, so the truncation error is ~1e-14·lever², far below
/// what the estimator resolves.
pub fn error_jacobian(
    order: &StackingOrder,
    q: &Vector3<f64>,
    tool: &Vector3<f64>,
    errors: &MachineErrors,
    tracker: &InstrumentPose,
) -> Result<nalgebra::SMatrix<f64, 3, 21>, KinematicsError> {
    let base = errors.to_vector();
    let mut failure = None;
    let point = |v: &[f64]| {
        let e = MachineErrors::from_vector(&nalgebra::SVector::<f64, 21>::from_column_slice(v));
        match tracker_point(order, q, tool, &e, tracker) {
            Ok(p) => Some(nalgebra::DVector::from_column_slice(p.as_slice())),
            Err(err) => {
                failure.get_or_insert(err);
                None
            }
        }
    };
    let jac = central_difference(point, base.as_slice(), &[1e-7; 21], Order::Second);
    match (jac, failure) {
        (_, Some(err)) => Err(err),
        (Some(j), None) => Ok(nalgebra::SMatrix::<f64, 3, 21>::from_column_slice(
            j.as_slice(),
        )),
        // The closure fails only through tracker_point, whose error is kept above.
        (None, None) => Err(KinematicsError::InvalidValue {
            field: "error_jacobian".into(),
            value: f64::NAN,
            reason: "central difference failed".into(),
        }),
    }
}
