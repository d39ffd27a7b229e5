//! Closed-form initial intrinsics from plane homographies (Zhang 2000) and per-view extrinsics.
//!
//! Zero skew is imposed (B12 = 0), so 5 unknowns (B11, B22, B13, B23, B33) up to scale, at least two
//! views. Homographies are first conditioned by the pixel normalisation N (centre of the image,
//! scale (w+h)/2) so that the linear system is well scaled; K = N·K'.

use crate::error::{CameraError, Result};
use crate::pose::Pose;
use nalgebra::{DMatrix, Matrix3, Rotation3, Vector3};

/// (fx, fy, cx, cy) from ≥ 2 homographies (object plane → pixels).
pub fn intrinsics_from_homographies(
    hs: &[Matrix3<f64>],
    width: u32,
    height: u32,
) -> Result<[f64; 4]> {
    let deg = |r: String| CameraError::Degenerate {
        what: "Zhang closed-form intrinsics".into(),
        reason: r,
    };
    if hs.len() < 2 {
        return Err(CameraError::TooFewPoints {
            what: "Zhang closed-form intrinsics (views)".into(),
            needed: 2,
            got: hs.len(),
        });
    }
    let s = (width + height) as f64 / 2.0;
    let (w2, h2) = (width as f64 / 2.0, height as f64 / 2.0);
    let n = Matrix3::new(s, 0.0, w2, 0.0, s, h2, 0.0, 0.0, 1.0);
    let n_inv = n.try_inverse().expect("N is invertible");
    let mut v = DMatrix::<f64>::zeros(2 * hs.len(), 5);
    for (k, h) in hs.iter().enumerate() {
        let mut hn = n_inv * h;
        hn /= hn.norm();
        let vij = |i: usize, j: usize| {
            let (a, b) = (hn.column(i), hn.column(j));
            [
                a[0] * b[0],
                a[1] * b[1],
                a[2] * b[0] + a[0] * b[2],
                a[2] * b[1] + a[1] * b[2],
                a[2] * b[2],
            ]
        };
        let v12 = vij(0, 1);
        let (v11, v22) = (vij(0, 0), vij(1, 1));
        for c in 0..5 {
            v[(2 * k, c)] = v12[c];
            v[(2 * k + 1, c)] = v11[c] - v22[c];
        }
    }
    let eig = nalgebra::SymmetricEigen::new(v.transpose() * &v);
    let b = eig.eigenvectors.column(eig.eigenvalues.imin()).into_owned();
    let b = if b[0] < 0.0 { -b } else { b };
    let (b11, b22, b13, b23, b33) = (b[0], b[1], b[2], b[3], b[4]);
    if !(b11 > 0.0 && b22 > 0.0) {
        return Err(deg(
            "image of the absolute conic is not positive definite (views too similar or too noisy)"
                .into(),
        ));
    }
    let v0 = -b23 / b22;
    let lambda = b33 - b13 * b13 / b11 + v0 * b23;
    if !(lambda / b11 > 0.0 && lambda / b22 > 0.0) {
        return Err(deg(format!("λ = {lambda:.3e} has the wrong sign")));
    }
    let alpha = (lambda / b11).sqrt();
    let beta = (lambda / b22).sqrt();
    let u0 = -b13 * alpha * alpha / lambda;
    let k = n * Matrix3::new(alpha, 0.0, u0, 0.0, beta, v0, 0.0, 0.0, 1.0);
    let out = [k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)]];
    if out.iter().any(|x| !x.is_finite()) {
        return Err(deg("non-finite intrinsics".into()));
    }
    Ok(out)
}

/// (fx, fy) with the principal point fixed at (cx, cy), from the two orthogonality constraints per
/// view (OpenCV's `initIntrinsicParams2D` idea). Used when the full closed form fails.
pub fn focal_from_homographies(hs: &[Matrix3<f64>], cx: f64, cy: f64) -> Result<[f64; 2]> {
    let shift = Matrix3::new(1.0, 0.0, -cx, 0.0, 1.0, -cy, 0.0, 0.0, 1.0);
    let mut a = DMatrix::<f64>::zeros(2 * hs.len(), 2);
    let mut rhs = nalgebra::DVector::<f64>::zeros(2 * hs.len());
    for (k, h) in hs.iter().enumerate() {
        let mut g = shift * h;
        g /= g.norm();
        // h1ᵀ diag(1/fx², 1/fy², 1) h2 = 0 and h1ᵀBh1 − h2ᵀBh2 = 0.
        a[(2 * k, 0)] = g[(0, 0)] * g[(0, 1)];
        a[(2 * k, 1)] = g[(1, 0)] * g[(1, 1)];
        rhs[2 * k] = -g[(2, 0)] * g[(2, 1)];
        a[(2 * k + 1, 0)] = g[(0, 0)].powi(2) - g[(0, 1)].powi(2);
        a[(2 * k + 1, 1)] = g[(1, 0)].powi(2) - g[(1, 1)].powi(2);
        rhs[2 * k + 1] = -(g[(2, 0)].powi(2) - g[(2, 1)].powi(2));
    }
    let sol = (a.transpose() * &a)
        .try_inverse()
        .map(|i| i * a.transpose() * rhs);
    match sol {
        Some(x) if x[0] > 0.0 && x[1] > 0.0 => Ok([1.0 / x[0].sqrt(), 1.0 / x[1].sqrt()]),
        _ => Err(CameraError::Degenerate {
            what: "focal length initialisation".into(),
            reason: "views give no positive focal length (all fronto-parallel?)".into(),
        }),
    }
}

/// Pose of the plane from H = K·[r1 r2 t] (up to scale), projected onto SO(3).
pub fn pose_from_homography(h: &Matrix3<f64>, k: &Matrix3<f64>) -> Result<Pose> {
    let a = k.try_inverse().ok_or_else(|| CameraError::Degenerate {
        what: "pose from homography".into(),
        reason: "K singular".into(),
    })? * h;
    let (a1, a2, a3) = (
        a.column(0).into_owned(),
        a.column(1).into_owned(),
        a.column(2).into_owned(),
    );
    let mut lambda = 2.0 / (a1.norm() + a2.norm());
    if a3.z * lambda < 0.0 {
        lambda = -lambda;
    }
    let r1 = a1 * lambda;
    let r2 = a2 * lambda;
    let r3 = r1.cross(&r2);
    let m = Matrix3::from_columns(&[r1, r2, r3]);
    let svd = m.svd(true, true);
    let mut r = svd.u.unwrap() * svd.v_t.unwrap();
    if r.determinant() < 0.0 {
        r = -r;
    }
    let t: Vector3<f64> = a3 * lambda;
    if !t.iter().all(|x| x.is_finite()) {
        return Err(CameraError::Degenerate {
            what: "pose from homography".into(),
            reason: "non-finite translation".into(),
        });
    }
    Ok(Pose {
        rotation: Rotation3::from_matrix_unchecked(r),
        translation: t,
    })
}
