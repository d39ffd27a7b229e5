//! Single-arm diagonal-rod correction of seed 002 (paper eqs 10–13, Salmerón Valdivieso), with the digest's
//! closed-form inverse. Eq. 12 as printed carries a spurious `− h*`; eq. 13 is the consistent form used here.
//!
//! Model: the effector moves by `L*` straight toward one tower; the firmware (rod `D0`, radius `R`) raises that
//! tower's carriage by `Dh = √(D0² − (R − L*)²) − h*`, `h* = √(D0² − R²)` (eqs 10–11). With the true rod `D`
//! the same rise gives the horizontal move `L = R − √(D² − (√(D² − R²) + Dh)²)` (eq. 13). Single arm only: a
//! real delta moves all three carriages, so one correction step under-corrects (iterate; digest T14).

use crate::error::{check_finite, KinematicsError};

fn sqrt_checked(v: f64, what: &str) -> Result<f64, KinematicsError> {
    if v < 0.0 {
        Err(KinematicsError::InvalidValue {
            field: what.to_string(),
            value: v,
            reason: "negative radicand: eq. 13 infeasible for these inputs".into(),
        })
    } else {
        Ok(v.sqrt())
    }
}

fn check_inputs(values: &[(&str, f64)]) -> Result<(), KinematicsError> {
    for (n, v) in values {
        check_finite(n, *v)?;
        if *v <= 0.0 {
            return Err(KinematicsError::InvalidValue {
                field: n.to_string(),
                value: *v,
                reason: "must be > 0".into(),
            });
        }
    }
    Ok(())
}

/// Eq. 10: carriage height above the effector with the effector centred, `h* = √(D0² − R²)`.
pub fn centre_carriage_height(d0: f64, radius: f64) -> Result<f64, KinematicsError> {
    check_inputs(&[("D0", d0), ("R", radius)])?;
    sqrt_checked(d0 * d0 - radius * radius, "D0² − R²")
}

/// Eq. 11: carriage rise `Dh` the firmware commands for a move of `l_star` toward the tower.
pub fn carriage_rise(d0: f64, radius: f64, l_star: f64) -> Result<f64, KinematicsError> {
    check_inputs(&[("L*", l_star)])?;
    Ok(
        sqrt_checked(d0 * d0 - (radius - l_star).powi(2), "D0² − (R − L*)²")?
            - centre_carriage_height(d0, radius)?,
    )
}

/// Eq. 13: true horizontal move `L` for commanded `l_star` when the real rod is `d_true`.
pub fn single_arm_move(
    d0: f64,
    radius: f64,
    l_star: f64,
    d_true: f64,
) -> Result<f64, KinematicsError> {
    check_inputs(&[("D", d_true)])?;
    let dh = carriage_rise(d0, radius, l_star)?;
    let h = sqrt_checked(d_true * d_true - radius * radius, "D² − R²")? + dh;
    Ok(radius - sqrt_checked(d_true * d_true - h * h, "D² − (√(D² − R²) + Dh)²")?)
}

/// Closed-form inverse of eq. 13: the real rod `D` from the measured move `l_measured` for commanded `l_star`:
/// `D = √(R² + ((R² − (R − L)² − Dh²) / (2 Dh))²)`, valid for `Dh > 0` and a positive bracket.
pub fn rod_from_measured_move(
    d0: f64,
    radius: f64,
    l_star: f64,
    l_measured: f64,
) -> Result<f64, KinematicsError> {
    check_inputs(&[("L", l_measured)])?;
    let dh = carriage_rise(d0, radius, l_star)?;
    if dh <= 0.0 {
        return Err(KinematicsError::InvalidValue {
            field: "Dh".into(),
            value: dh,
            reason: "carriage rise must be > 0 (0 < L* < 2R)".into(),
        });
    }
    let bracket = (radius * radius - (radius - l_measured).powi(2) - dh * dh) / (2.0 * dh);
    if bracket <= 0.0 {
        return Err(KinematicsError::InvalidValue {
            field: "√(D² − R²)".into(),
            value: bracket,
            reason: "measured move implies no real rod length".into(),
        });
    }
    Ok((radius * radius + bracket * bracket).sqrt())
}
