//! Object-plane scale from a target of known size (seed 002, eq. 4, with its erratum: the ratio
//! L_mm / L_px is millimetres per pixel, not px/mm).

use crate::error::{invalid, Result};

/// Scale on the target plane, (length unit of `known_length`) per pixel, with its standard
/// uncertainty propagated from the pixel-length uncertainty: s = L / L_px, u(s) = s · u(L_px) / L_px.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneScale {
    pub per_pixel: f64,
    pub std: f64,
}

/// `known_length` (e.g. a 10 mm checkerboard square) spanning `length_px` pixels, measured with
/// standard uncertainty `length_px_std`.
pub fn plane_scale(known_length: f64, length_px: f64, length_px_std: f64) -> Result<PlaneScale> {
    if !(known_length.is_finite() && known_length > 0.0) {
        return Err(invalid(
            "known_length",
            format!("{known_length} must be positive"),
        ));
    }
    if !(length_px.is_finite() && length_px > 0.0) {
        return Err(invalid(
            "length_px",
            format!("{length_px} must be positive"),
        ));
    }
    if !(length_px_std.is_finite() && length_px_std >= 0.0) {
        return Err(invalid(
            "length_px_std",
            format!("{length_px_std} must be ≥ 0"),
        ));
    }
    let s = known_length / length_px;
    Ok(PlaneScale {
        per_pixel: s,
        std: s * length_px_std / length_px,
    })
}

/// Mean square side in pixels of a rectified checkerboard: corners row-major, `cols` per row;
/// averages every horizontal and vertical neighbour distance. Returns (mean, standard error).
pub fn mean_square_side_px(corners: &[[f64; 2]], cols: usize) -> Result<(f64, f64)> {
    if cols < 2 || corners.len() < 2 * cols || corners.len() % cols != 0 {
        return Err(invalid(
            "corners",
            format!(
                "{} corners do not form a grid of ≥ 2×2 with {cols} columns",
                corners.len()
            ),
        ));
    }
    let rows = corners.len() / cols;
    let mut d = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let p = corners[r * cols + c];
            if c + 1 < cols {
                let q = corners[r * cols + c + 1];
                d.push(((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt());
            }
            if r + 1 < rows {
                let q = corners[(r + 1) * cols + c];
                d.push(((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt());
            }
        }
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    Ok((mean, (var / n).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_002_eq4_scale() {
        // A 10 mm square spanning 138.389 px gives 0.07226 mm/px (seed 002, Table 2).
        let s = plane_scale(10.0, 138.389, 0.5).unwrap();
        assert!((s.per_pixel - 0.07226).abs() < 0.5e-5, "{}", s.per_pixel);
        assert!((s.std - 0.07226 * 0.5 / 138.389).abs() < 1e-7);
        // The seed's ±0.578 mm = 8 px × 0.07226 mm/px.
        assert!((8.0 * s.per_pixel - 0.578).abs() < 0.5e-3);
        assert!(plane_scale(10.0, 0.0, 0.1).is_err());
    }

    #[test]
    fn square_side_from_grid() {
        let corners: Vec<[f64; 2]> = (0..12)
            .map(|i| {
                [
                    100.0 + 138.389 * (i % 4) as f64,
                    50.0 + 138.389 * (i / 4) as f64,
                ]
            })
            .collect();
        let (m, se) = mean_square_side_px(&corners, 4).unwrap();
        assert!((m - 138.389).abs() < 1e-9 && se < 1e-9);
    }
}
