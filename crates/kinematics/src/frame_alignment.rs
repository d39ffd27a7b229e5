//! Aligning a machine's tool frame with the frame of a camera riding on the tool (patent ES 2 664 936 T3 /
//! EP 3088843, seed 003 digest), from pure translations and pure rotations.
//!
//! Conventions (the digest's §6.2 test conventions; the patent fixes none):
//! - `R_rc` maps camera-frame vectors into robot-frame vectors; a pure robot translation `v` is read by the
//!   camera as `c = R_rcᵀ v`.
//! - `r` is the camera origin relative to the rotation axis (aligned frame); `Des = tool origin − camera origin
//!   = −r` when the first axis passes through the tool origin; `Desp = axis 2 − axis 1`.
//! - Camera displacements `CΔ` are expressed in the fixed CP0-aligned frame; a rotation by θ about an axis
//!   through `a` moves the camera by `Δ = (R(θ) − I)(camera − a)`.
//! - Ratio equations (patent steps 116 and 124): `Des_x / CΔy1 = (Des_x + Desp_x) / CΔy2`,
//!   `Des_y / CΔx1 = (Des_y + Desp_y) / CΔx2`, solved as `Des = Desp · CΔ1 / (CΔ2 − CΔ1)`; the same with two x
//!   axes (CΔy) or two y axes (CΔx) for `Des_z`. Errata honoured: CΔx2 is the x component (the patent's text
//!   says "y"); a zero axis-offset component would silently return 0 and is rejected instead.

use crate::error::KinematicsError;
use crate::rigid_registration::kabsch_rotation;
use nalgebra::{Matrix2, Matrix3, Unit, UnitQuaternion, Vector2, Vector3};

/// Twin output: what the camera reads for a pure robot translation `robot_move` (`c = R_rcᵀ v`).
pub fn camera_reading_of_translation(
    r_rc: &Matrix3<f64>,
    robot_move: &Vector3<f64>,
) -> Vector3<f64> {
    r_rc.transpose() * robot_move
}

/// Twin output: displacement of the camera origin when the tool turns by `angle` about the axis of direction
/// `axis` through `axis_point` (aligned frame): `Δ = (R(θ) − I)(camera − axis_point)`.
pub fn camera_displacement_of_rotation(
    axis: &Unit<Vector3<f64>>,
    angle: f64,
    axis_point: &Vector3<f64>,
    camera: &Vector3<f64>,
) -> Vector3<f64> {
    let r = camera - axis_point;
    UnitQuaternion::from_axis_angle(axis, angle) * r - r
}

fn triad(a: &Vector3<f64>, b: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let e1 = a.try_normalize(1e-300)?;
    let e3 = a.cross(b).try_normalize(1e-12 * a.norm() * b.norm())?;
    let e2 = e3.cross(&e1);
    Some(Matrix3::from_columns(&[e1, e2, e3]))
}

/// TRIAD rotation `R_rc` from two non-collinear robot moves `v1, v2` and the camera's readings `c1, c2`.
pub fn rotation_from_two_moves(
    v1: &Vector3<f64>,
    v2: &Vector3<f64>,
    c1: &Vector3<f64>,
    c2: &Vector3<f64>,
) -> Result<Matrix3<f64>, KinematicsError> {
    let mv = triad(v1, v2).ok_or_else(|| KinematicsError::Degenerate {
        reason: "robot moves are collinear or zero".into(),
    })?;
    let mc = triad(c1, c2).ok_or_else(|| KinematicsError::Degenerate {
        reason: "camera moves are collinear or zero".into(),
    })?;
    Ok(mv * mc.transpose())
}

/// Kabsch/SVD least-squares rotation `R_rc` minimising `Σ |v_i − R c_i|²` over N ≥ 2 non-collinear moves
/// (the workspace's one Kabsch, [`crate::rigid_registration::kabsch_rotation`], camera moves → robot moves).
pub fn rotation_kabsch(
    robot_moves: &[Vector3<f64>],
    camera_moves: &[Vector3<f64>],
) -> Result<Matrix3<f64>, KinematicsError> {
    kabsch_rotation(camera_moves, robot_moves, None)
}

/// Yaw (rotation about z) of a rotation matrix, `atan2(R10, R00)` (rad).
pub fn yaw(r: &Matrix3<f64>) -> f64 {
    r[(1, 0)].atan2(r[(0, 0)])
}

/// One ratio equation `Des / CΔ1 = (Des + Desp) / CΔ2` solved for `Des = Desp·CΔ1 / (CΔ2 − CΔ1)`; `what` names
/// the component in errors.
pub fn ratio_misalignment(desp: f64, d1: f64, d2: f64, what: &str) -> Result<f64, KinematicsError> {
    if desp.abs() < 1e-15 {
        return Err(KinematicsError::Degenerate { reason: format!("{what}: axis offset component is zero, the ratio equation would return 0 regardless of the truth") });
    }
    let den = d2 - d1;
    if den.abs() <= 1e-12 * (d1.abs() + d2.abs()).max(f64::MIN_POSITIVE) {
        return Err(KinematicsError::Degenerate {
            reason: format!(
                "{what}: camera displacements about the two axes are equal (CΔ2 − CΔ1 ≈ 0)"
            ),
        });
    }
    Ok(desp * d1 / den)
}

/// Patent step 116: `(Des_x, Des_y)` from the offset `desp = (Desp_x, Desp_y)` between two parallel z axes and the
/// camera displacements `cd1`, `cd2` (x, y components) for equal rotations about them.
pub fn xy_misalignment(
    desp: Vector2<f64>,
    cd1: Vector2<f64>,
    cd2: Vector2<f64>,
) -> Result<Vector2<f64>, KinematicsError> {
    Ok(Vector2::new(
        ratio_misalignment(desp.x, cd1.y, cd2.y, "Des_x")?,
        ratio_misalignment(desp.y, cd1.x, cd2.x, "Des_y")?,
    ))
}

/// Patent step 124 (two parallel x axes offset by `desp_z`): `Des_z` from the camera's y displacements.
pub fn z_misalignment_from_x_axes(
    desp_z: f64,
    cdy1: f64,
    cdy2: f64,
) -> Result<f64, KinematicsError> {
    ratio_misalignment(desp_z, cdy1, cdy2, "Des_z (x axes)")
}

/// Patent step 124, variant with two parallel y axes: `Des_z` from the camera's x displacements.
pub fn z_misalignment_from_y_axes(
    desp_z: f64,
    cdx1: f64,
    cdx2: f64,
) -> Result<f64, KinematicsError> {
    ratio_misalignment(desp_z, cdx1, cdx2, "Des_z (y axes)")
}

/// Exact alternative (digest §2.3): the camera offset `r` from one rotation θ ≠ 0 about z, `r = (Rz(θ) − I)⁻¹ Δ`.
pub fn offset_from_rotation_about_z(
    angle: f64,
    delta: Vector2<f64>,
) -> Result<Vector2<f64>, KinematicsError> {
    let (s, c) = angle.sin_cos();
    let m = Matrix2::new(c - 1.0, -s, s, c - 1.0);
    m.try_inverse()
        .map(|mi| mi * delta)
        .ok_or_else(|| KinematicsError::Degenerate {
            reason: "rotation angle is zero".into(),
        })
}

/// One pass of the patent's xy stage, simulated on the twin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XyAlignmentPass {
    /// The pass's estimate `(Des_x, Des_y)`.
    pub estimate: Vector2<f64>,
    /// Camera xy offset from the tool origin left after translating the frame by the estimate.
    pub residual: Vector2<f64>,
}

/// Twin simulation of the iterated xy stage (claims 8–9): true camera xy offset `r` (aligned frame: `r = R_rcᵀ r_tool` for an offset `r_tool` given in the tool frame), rotations
/// by `angle` about the z axis through the current frame origin and about one offset by `desp`; each pass
/// translates the frame by its estimate. Measurements are noise-free and multiplied by `camera_scale`.
pub fn simulate_xy_alignment(
    r: Vector2<f64>,
    angle: f64,
    desp: Vector2<f64>,
    camera_scale: f64,
    passes: usize,
) -> Result<Vec<XyAlignmentPass>, KinematicsError> {
    let z = Vector3::z_axis();
    let mut residual = r;
    let mut out = Vec::with_capacity(passes);
    for _ in 0..passes {
        let cam = Vector3::new(residual.x, residual.y, 0.0);
        let d1 = camera_displacement_of_rotation(&z, angle, &Vector3::zeros(), &cam) * camera_scale;
        let d2 =
            camera_displacement_of_rotation(&z, angle, &Vector3::new(desp.x, desp.y, 0.0), &cam)
                * camera_scale;
        let estimate = xy_misalignment(desp, d1.xy(), d2.xy())?;
        residual += estimate;
        out.push(XyAlignmentPass { estimate, residual });
    }
    Ok(out)
}
