//! Plane-to-plane homography from four point pairs (exact DLT solve).

use nalgebra::{Matrix3, SMatrix, SVector};

/// H with H·(src, 1) ∝ (dst, 1) for the four pairs. None if degenerate.
pub fn homography_4pt(src: &[[f64; 2]; 4], dst: &[[f64; 2]; 4]) -> Option<Matrix3<f64>> {
    let mut a = SMatrix::<f64, 8, 8>::zeros();
    let mut b = SVector::<f64, 8>::zeros();
    for k in 0..4 {
        let ([x, y], [u, v]) = (src[k], dst[k]);
        a.row_mut(2 * k)
            .copy_from_slice(&[x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y]);
        a.row_mut(2 * k + 1)
            .copy_from_slice(&[0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y]);
        b[2 * k] = u;
        b[2 * k + 1] = v;
    }
    let h = a.lu().solve(&b)?;
    if !h.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(Matrix3::new(
        h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0,
    ))
}

/// Apply H to a point.
#[inline]
pub fn apply(h: &Matrix3<f64>, x: f64, y: f64) -> [f64; 2] {
    let w = h[(2, 0)] * x + h[(2, 1)] * y + h[(2, 2)];
    [
        (h[(0, 0)] * x + h[(0, 1)] * y + h[(0, 2)]) / w,
        (h[(1, 0)] * x + h[(1, 1)] * y + h[(1, 2)]) / w,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_the_four_points() {
        let src = [[0.0, 0.0], [6.0, 0.0], [6.0, 6.0], [0.0, 6.0]];
        let dst = [[10.0, 12.0], [70.0, 15.0], [66.0, 80.0], [8.0, 70.0]];
        let h = homography_4pt(&src, &dst).unwrap();
        for k in 0..4 {
            let p = apply(&h, src[k][0], src[k][1]);
            assert!((p[0] - dst[k][0]).abs() < 1e-9 && (p[1] - dst[k][1]).abs() < 1e-9);
        }
    }
}
