//! Linear delta (three vertical towers, parallelogram rods), Marlin conventions.
//!
//! Frame: origin on the print-bed centre line, z up; tower `T` sits in plan at angle
//! `φ_T = base_T + tower_angle_trim_T` with bases 210° (A, front left), 330° (B, front right), 90° (C, back),
//! at radius `R + radius_trim_T` (Marlin `recalc_delta_settings()`). `R` is Marlin's `DELTA_RADIUS`: the
//! horizontal distance carriage joint ↔ effector joint with the effector centred. Rod `D_T = D + rod_trim_T`
//! (`DELTA_DIAGONAL_ROD + diag_rod_trim`).
//!
//! Joint coordinates `q_T` are the carriage heights as the firmware counts them. The endstop offset `e_T` is the
//! physical carriage height minus the firmware's count (a switch that trips `e_T` high makes the real carriage
//! `e_T` higher than counted), so IK is `q_T = z + √(D_T² − (x_T − x)² − (y_T − y)²) − e_T` (Marlin `DELTA_IK`
//! with `e_T = 0`), and FK trilaterates spheres of radius `D_T` about `(x_T, y_T, q_T + e_T)`, taking the
//! effector below the carriages.

use crate::error::{check_finite, KinematicsError};
use nalgebra::{Matrix3, SMatrix, Vector2, Vector3};

/// Nominal Marlin tower angles A, B, C in radians (210°, 330°, 90°).
pub const MARLIN_TOWER_BASE_ANGLES: [f64; 3] = [
    210.0 * std::f64::consts::PI / 180.0,
    330.0 * std::f64::consts::PI / 180.0,
    90.0 * std::f64::consts::PI / 180.0,
];

/// Geometric parameters of a linear delta (SI: metres, radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeltaGeometry {
    /// `DELTA_DIAGONAL_ROD` D (m).
    pub rod_length: f64,
    /// `DELTA_RADIUS` R (m).
    pub radius: f64,
    /// `DELTA_TOWER_ANGLE_TRIM` per tower A, B, C (rad), added to 210°, 330°, 90°.
    pub tower_angle_trim: [f64; 3],
    /// `DELTA_RADIUS_TRIM_TOWER` per tower (m).
    pub radius_trim: [f64; 3],
    /// Diagonal-rod trim per tower (m).
    pub rod_trim: [f64; 3],
    /// Endstop offset per tower (m): physical carriage height minus firmware count.
    pub endstop: [f64; 3],
}

/// Index of each scalar parameter in [`DeltaGeometry::to_vector`] / the columns of the parameter Jacobians.
pub const DELTA_PARAMETER_NAMES: [&str; 14] = [
    "delta_rod_length",
    "delta_radius",
    "delta_tower_angle_a",
    "delta_tower_angle_b",
    "delta_tower_angle_c",
    "delta_radius_trim_a",
    "delta_radius_trim_b",
    "delta_radius_trim_c",
    "delta_rod_trim_a",
    "delta_rod_trim_b",
    "delta_rod_trim_c",
    "delta_endstop_a",
    "delta_endstop_b",
    "delta_endstop_c",
];

/// Number of geometric parameters of [`DeltaGeometry`].
pub const DELTA_PARAMETER_COUNT: usize = 14;

impl DeltaGeometry {
    /// Nominal delta: all trims and endstops zero.
    pub fn new(rod_length: f64, radius: f64) -> Result<Self, KinematicsError> {
        let g = Self {
            rod_length,
            radius,
            tower_angle_trim: [0.0; 3],
            radius_trim: [0.0; 3],
            rod_trim: [0.0; 3],
            endstop: [0.0; 3],
        };
        g.validate()?;
        Ok(g)
    }

    /// Checks that every parameter is finite and that rods and radii are positive.
    pub fn validate(&self) -> Result<(), KinematicsError> {
        for (i, v) in self.to_vector().iter().enumerate() {
            check_finite(DELTA_PARAMETER_NAMES[i], *v)?;
        }
        for t in 0..3 {
            if self.rod(t) <= 0.0 {
                return Err(KinematicsError::InvalidValue {
                    field: format!("rod length of tower {t}"),
                    value: self.rod(t),
                    reason: "must be > 0".into(),
                });
            }
            if self.radius + self.radius_trim[t] <= 0.0 {
                return Err(KinematicsError::InvalidValue {
                    field: format!("radius of tower {t}"),
                    value: self.radius + self.radius_trim[t],
                    reason: "must be > 0".into(),
                });
            }
        }
        Ok(())
    }

    /// Parameters as a vector in the order of [`DELTA_PARAMETER_NAMES`].
    pub fn to_vector(&self) -> SMatrix<f64, DELTA_PARAMETER_COUNT, 1> {
        let mut v = SMatrix::<f64, DELTA_PARAMETER_COUNT, 1>::zeros();
        v[0] = self.rod_length;
        v[1] = self.radius;
        for t in 0..3 {
            v[2 + t] = self.tower_angle_trim[t];
            v[5 + t] = self.radius_trim[t];
            v[8 + t] = self.rod_trim[t];
            v[11 + t] = self.endstop[t];
        }
        v
    }

    /// Inverse of [`Self::to_vector`].
    pub fn from_vector(v: &SMatrix<f64, DELTA_PARAMETER_COUNT, 1>) -> Self {
        let mut g = Self {
            rod_length: v[0],
            radius: v[1],
            tower_angle_trim: [0.0; 3],
            radius_trim: [0.0; 3],
            rod_trim: [0.0; 3],
            endstop: [0.0; 3],
        };
        for t in 0..3 {
            g.tower_angle_trim[t] = v[2 + t];
            g.radius_trim[t] = v[5 + t];
            g.rod_trim[t] = v[8 + t];
            g.endstop[t] = v[11 + t];
        }
        g
    }

    /// Rod length of tower `t` including its trim.
    pub fn rod(&self, t: usize) -> f64 {
        self.rod_length + self.rod_trim[t]
    }

    /// Plan angle of tower `t` (rad).
    pub fn tower_angle(&self, t: usize) -> f64 {
        MARLIN_TOWER_BASE_ANGLES[t] + self.tower_angle_trim[t]
    }

    /// Plan position (x, y) of tower `t`'s carriage joint line (m).
    pub fn tower_xy(&self, t: usize) -> Vector2<f64> {
        let r = self.radius + self.radius_trim[t];
        let a = self.tower_angle(t);
        Vector2::new(r * a.cos(), r * a.sin())
    }

    /// Inverse kinematics: firmware carriage heights `q` (m) for effector position `p` (m).
    pub fn inverse(&self, p: &Vector3<f64>) -> Result<[f64; 3], KinematicsError> {
        self.validate()?;
        for (i, v) in p.iter().enumerate() {
            check_finite(["x", "y", "z"][i], *v)?;
        }
        let mut q = [0.0; 3];
        for (t, qt) in q.iter_mut().enumerate() {
            let d = self.tower_xy(t) - p.xy();
            let rod = self.rod(t);
            let rad = rod * rod - d.norm_squared();
            if rad <= 0.0 {
                return Err(KinematicsError::DeltaUnreachable {
                    tower: t,
                    horizontal_distance: d.norm(),
                    rod_length: rod,
                });
            }
            *qt = p.z + rad.sqrt() - self.endstop[t];
        }
        Ok(q)
    }

    /// Forward kinematics by trilateration: effector position (m) from firmware carriage heights `q` (m).
    /// Of the two sphere intersections the lower one (effector below the carriages) is returned.
    pub fn forward(&self, q: &[f64; 3]) -> Result<Vector3<f64>, KinematicsError> {
        self.validate()?;
        for (t, v) in q.iter().enumerate() {
            check_finite(&format!("carriage height of tower {t}"), *v)?;
        }
        let c: Vec<Vector3<f64>> = (0..3)
            .map(|t| {
                let xy = self.tower_xy(t);
                Vector3::new(xy.x, xy.y, q[t] + self.endstop[t])
            })
            .collect();
        let r = [self.rod(0), self.rod(1), self.rod(2)];
        // Orthonormal frame with c0 at origin, ex towards c1, ey in the plane of the three centres.
        let d01 = c[1] - c[0];
        let dist01 = d01.norm();
        if dist01 < 1e-12 {
            return Err(KinematicsError::DeltaDegenerate {
                reason: "towers A and B coincide".into(),
            });
        }
        let ex = d01 / dist01;
        let d02 = c[2] - c[0];
        let i = ex.dot(&d02);
        let ey_raw = d02 - ex * i;
        let j = ey_raw.norm();
        if j < 1e-12 {
            return Err(KinematicsError::DeltaDegenerate {
                reason: "the three carriage joints are collinear".into(),
            });
        }
        let ey = ey_raw / j;
        let ez = ex.cross(&ey);
        let x = (r[0] * r[0] - r[1] * r[1] + dist01 * dist01) / (2.0 * dist01);
        let y = (r[0] * r[0] - r[2] * r[2] + i * i + j * j) / (2.0 * j) - (i / j) * x;
        let z2 = r[0] * r[0] - x * x - y * y;
        if z2 < 0.0 {
            return Err(KinematicsError::DeltaNoIntersection { heights: *q });
        }
        let z = z2.sqrt();
        let base = c[0] + ex * x + ey * y;
        let p1 = base + ez * z;
        let p2 = base - ez * z;
        Ok(if p1.z < p2.z { p1 } else { p2 })
    }

    /// Jacobian `∂q/∂p` (3×3) of the inverse kinematics at effector position `p`.
    pub fn inverse_jacobian(&self, p: &Vector3<f64>) -> Result<Matrix3<f64>, KinematicsError> {
        let q = self.inverse(p)?;
        let mut j = Matrix3::zeros();
        for t in 0..3 {
            let xy = self.tower_xy(t);
            let s = q[t] + self.endstop[t] - p.z; // √(D² − ρ²)
            j[(t, 0)] = (xy.x - p.x) / s;
            j[(t, 1)] = (xy.y - p.y) / s;
            j[(t, 2)] = 1.0;
        }
        Ok(j)
    }

    /// Jacobian `∂q/∂θ` (3×14) of the inverse kinematics w.r.t. the geometric parameters
    /// (columns in [`DELTA_PARAMETER_NAMES`] order) at effector position `p`. Analytic.
    pub fn inverse_parameter_jacobian(
        &self,
        p: &Vector3<f64>,
    ) -> Result<SMatrix<f64, 3, DELTA_PARAMETER_COUNT>, KinematicsError> {
        let q = self.inverse(p)?;
        let mut j = SMatrix::<f64, 3, DELTA_PARAMETER_COUNT>::zeros();
        for t in 0..3 {
            let xy = self.tower_xy(t);
            let s = q[t] + self.endstop[t] - p.z;
            let rod = self.rod(t);
            let a = self.tower_angle(t);
            let dxy = xy - p.xy();
            // ∂s/∂D_T = D_T / s ; ∂s/∂(tower xy) = −(xy − p)/s
            j[(t, 0)] = rod / s;
            j[(t, 8 + t)] = rod / s;
            let dir = Vector2::new(a.cos(), a.sin());
            let d_radius = -dxy.dot(&dir) / s;
            j[(t, 1)] = d_radius;
            j[(t, 5 + t)] = d_radius;
            let r = self.radius + self.radius_trim[t];
            let d_angle = -dxy.dot(&Vector2::new(-r * a.sin(), r * a.cos())) / s;
            j[(t, 2 + t)] = d_angle;
            j[(t, 11 + t)] = -1.0;
        }
        Ok(j)
    }

    /// Jacobian `∂p/∂θ` (3×14) of the forward kinematics w.r.t. the geometric parameters, with the firmware
    /// carriage heights `q` held fixed. Analytic, by the implicit-function theorem on
    /// `q_T − IK_T(p, θ) = 0`: `∂p/∂θ = −(∂IK/∂p)⁻¹ · ∂IK/∂θ`.
    pub fn forward_parameter_jacobian(
        &self,
        q: &[f64; 3],
    ) -> Result<SMatrix<f64, 3, DELTA_PARAMETER_COUNT>, KinematicsError> {
        let p = self.forward(q)?;
        let jp = self.inverse_jacobian(&p)?;
        let jth = self.inverse_parameter_jacobian(&p)?;
        let inv = jp
            .try_inverse()
            .ok_or_else(|| KinematicsError::DeltaDegenerate {
                reason: format!("IK Jacobian singular at {p:?}"),
            })?;
        Ok(-(inv * jth))
    }
}
