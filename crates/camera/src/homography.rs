//! Plane-to-image homography by the normalised direct linear transform (Hartley): the one
//! homography of the workspace (calibration, IPPE's planar pose, crates/vision's marker decoding).
//!
//! H maps homogeneous source points (X, Y, 1) to destination points: dst ~ H·src, scaled so that
//! ‖H‖_F = 1 and H\[2,2\] ≥ 0.

use crate::error::{CameraError, Result};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// Isotropic normalisation: centroid to origin, mean distance √2. Returns None for coincident points.
fn normalisation(pts: &[[f64; 2]]) -> Option<Matrix3<f64>> {
    let n = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p[0] / n, a.1 + p[1] / n));
    let mean_d = pts
        .iter()
        .map(|p| ((p[0] - mx).powi(2) + (p[1] - my).powi(2)).sqrt())
        .sum::<f64>()
        / n;
    if !(mean_d > 0.0) || !mean_d.is_finite() {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / mean_d;
    Some(Matrix3::new(
        s,
        0.0,
        -s * mx,
        0.0,
        s,
        -s * my,
        0.0,
        0.0,
        1.0,
    ))
}

/// Applies H to (x, y); None when the point maps to infinity.
pub fn apply(h: &Matrix3<f64>, p: [f64; 2]) -> Option<[f64; 2]> {
    let q = h * Vector3::new(p[0], p[1], 1.0);
    if q.z.abs() < 1e-300 {
        return None;
    }
    Some([q.x / q.z, q.y / q.z])
}

/// Normalised DLT homography from ≥ 4 correspondences.
///
/// Errors: fewer than 4 points, non-finite input, or a degenerate configuration (collinear or
/// coincident points: the second-smallest singular value of the normalised system is below
/// 1e-9 of the largest, or H is singular).
pub fn homography_dlt(src: &[[f64; 2]], dst: &[[f64; 2]]) -> Result<Matrix3<f64>> {
    let what = "homography";
    if src.len() != dst.len() {
        return Err(CameraError::InvalidParameter {
            name: "points".into(),
            reason: format!("{} source vs {} destination points", src.len(), dst.len()),
        });
    }
    if src.len() < 4 {
        return Err(CameraError::TooFewPoints {
            what: what.into(),
            needed: 4,
            got: src.len(),
        });
    }
    for (i, (a, b)) in src.iter().zip(dst).enumerate() {
        if !(a[0].is_finite() && a[1].is_finite() && b[0].is_finite() && b[1].is_finite()) {
            return Err(CameraError::BadPoint {
                index: i,
                reason: "non-finite coordinate".into(),
            });
        }
    }
    let degenerate = |r: &str| CameraError::Degenerate {
        what: what.into(),
        reason: r.into(),
    };
    let ts = normalisation(src).ok_or_else(|| degenerate("coincident source points"))?;
    let td = normalisation(dst).ok_or_else(|| degenerate("coincident image points"))?;
    let n = src.len();
    let mut a = DMatrix::<f64>::zeros(2 * n, 9);
    for i in 0..n {
        let s = ts * Vector3::new(src[i][0], src[i][1], 1.0);
        let d = td * Vector3::new(dst[i][0], dst[i][1], 1.0);
        let (x, y) = (s.x, s.y);
        let (u, v) = (d.x, d.y);
        let r0 = [x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y, -u];
        let r1 = [0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y, -v];
        for j in 0..9 {
            a[(2 * i, j)] = r0[j];
            a[(2 * i + 1, j)] = r1[j];
        }
    }
    // Smallest eigenvector of AᵀA (9×9, symmetric); well conditioned after normalisation.
    let ata = a.transpose() * &a;
    let eig = nalgebra::SymmetricEigen::new(ata);
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&i, &j| {
        eig.eigenvalues[i]
            .partial_cmp(&eig.eigenvalues[j])
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let (l_min2, l_max) = (
        eig.eigenvalues[order[1]].max(0.0),
        eig.eigenvalues[order[8]],
    );
    if !(l_max > 0.0) || (l_min2 / l_max).sqrt() < 1e-9 {
        return Err(degenerate(
            "points are collinear or coincident (rank-deficient DLT system)",
        ));
    }
    let h = eig.eigenvectors.column(order[0]);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let td_inv = td
        .try_inverse()
        .ok_or_else(|| degenerate("normalisation not invertible"))?;
    let mut hm = td_inv * hn * ts;
    let norm = hm.norm();
    if !(norm > 0.0) {
        return Err(degenerate("zero homography"));
    }
    hm /= norm;
    if hm[(2, 2)] < 0.0 {
        hm = -hm;
    }
    let sv = hm.singular_values();
    if sv[2] < 1e-12 * sv[0] {
        return Err(degenerate("singular homography (plane seen edge-on)"));
    }
    Ok(hm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_exact_homography_and_rejects_collinear() {
        let h_true = Matrix3::new(800.0, 20.0, 320.0, -15.0, 790.0, 240.0, 0.1, -0.05, 1.0);
        let src: Vec<[f64; 2]> = (0..20)
            .map(|i| [(i % 5) as f64 * 0.1, (i / 5) as f64 * 0.1])
            .collect();
        let dst: Vec<[f64; 2]> = src.iter().map(|p| apply(&h_true, *p).unwrap()).collect();
        let h = homography_dlt(&src, &dst).unwrap();
        for (s, d) in src.iter().zip(&dst) {
            let q = apply(&h, *s).unwrap();
            assert!((q[0] - d[0]).abs() < 1e-9 && (q[1] - d[1]).abs() < 1e-9);
        }
        let line: Vec<[f64; 2]> = (0..6).map(|i| [i as f64, 2.0 * i as f64]).collect();
        assert!(matches!(
            homography_dlt(&line, &line),
            Err(CameraError::Degenerate { .. })
        ));
        assert!(matches!(
            homography_dlt(&src[..3], &dst[..3]),
            Err(CameraError::TooFewPoints { .. })
        ));
    }

    #[test]
    fn four_points_give_the_exact_homography() {
        // what crates/vision's marker decoding asks of it: the unique H through four pairs
        let src = [[0.0, 0.0], [6.0, 0.0], [6.0, 6.0], [0.0, 6.0]];
        let dst = [[10.0, 12.0], [70.0, 15.0], [66.0, 80.0], [8.0, 70.0]];
        let h = homography_dlt(&src, &dst).unwrap();
        for (s, d) in src.iter().zip(&dst) {
            let p = apply(&h, *s).unwrap();
            assert!((p[0] - d[0]).abs() < 1e-9 && (p[1] - d[1]).abs() < 1e-9);
        }
        assert!((h.norm() - 1.0).abs() < 1e-15 && h[(2, 2)] >= 0.0);
    }
}
