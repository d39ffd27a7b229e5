//! Pixel-to-length scale on a plane (seed 002, eq. 4): R = L / L_px, in metres per pixel.
//! Valid for a plane seen fronto-parallel (after undistortion); under perspective the scale
//! varies across the image and `spread` shows by how much.

use crate::checkerboard::CheckerboardCorners;
use crate::error::{invalid, Result};

/// Eq. 4: metres per pixel from a known length `length_m` spanning `length_px` pixels.
pub fn scale_from_length(length_m: f64, length_px: f64) -> Result<f64> {
    if !(length_m.is_finite() && length_m > 0.0) {
        return Err(invalid(
            "length_m",
            format!("must be finite and > 0, got {length_m}"),
        ));
    }
    if !(length_px.is_finite() && length_px > 0.0) {
        return Err(invalid(
            "length_px",
            format!("must be finite and > 0, got {length_px}"),
        ));
    }
    Ok(length_m / length_px)
}

/// Scale of a plane measured on a checkerboard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneScale {
    /// Mean metres per pixel over all adjacent-corner spacings.
    pub metres_per_pixel: f64,
    /// Standard uncertainty of that mean (m/px), from the corners' covariances.
    pub std: f64,
    /// Standard deviation of the per-spacing scales (m/px): perspective or board non-flatness.
    pub spread: f64,
    /// Number of spacings used.
    pub spacings: usize,
}

/// Eq. 4 applied to every pair of adjacent inner corners (squares of side `square_m`).
pub fn plane_scale_from_checkerboard(
    board: &CheckerboardCorners,
    square_m: f64,
) -> Result<PlaneScale> {
    if !(square_m.is_finite() && square_m > 0.0) {
        return Err(invalid(
            "square_m",
            format!("must be finite and > 0, got {square_m}"),
        ));
    }
    let mut scales = Vec::new();
    let mut var_sum = 0.0;
    for r in 0..board.rows {
        for c in 0..board.cols {
            for (dc, dr) in [(1, 0), (0, 1)] {
                if c + dc >= board.cols || r + dr >= board.rows {
                    continue;
                }
                let a = &board.corners[r * board.cols + c];
                let b = &board.corners[(r + dr) * board.cols + c + dc];
                let d = b.position - a.position;
                let len = d.norm();
                let s = scale_from_length(square_m, len)?;
                // var(len) = uᵀ(Σa + Σb)u; var(s) = (s/len)² var(len)
                let u = d / len;
                let var_len = (u.transpose() * (a.covariance + b.covariance) * u)[(0, 0)];
                var_sum += (s / len).powi(2) * var_len;
                scales.push(s);
            }
        }
    }
    let n = scales.len() as f64;
    let mean = scales.iter().sum::<f64>() / n;
    let spread =
        (scales.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
    // Spacings share corners, so treat them as fully correlated for a conservative bound.
    let std = var_sum.sqrt() / n.sqrt().max(1.0);
    Ok(PlaneScale {
        metres_per_pixel: mean,
        std,
        spread,
        spacings: scales.len(),
    })
}
