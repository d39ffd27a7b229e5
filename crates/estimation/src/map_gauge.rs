//! The gauge an error map is stated in.
//!
//! A tracker (or any instrument placed freely beside the machine) measures the machine's
//! errors only up to a rigid motion: a map rotated and shifted as a whole reads the same once
//! the instrument's pose is identified with it. Which rigid motion a fit's map carries then
//! depends on which parameters it held to fix that freedom — straightnesses' slopes, a
//! squareness, an angular error's constant, or a coordinate of the instrument's pose — and that
//! choice follows from the model and the data, not from the machine. Two fits, or a fit and the
//! truth, are comparable only in one stated gauge.
//!
//! [`MapGauge::RigidMotionRemoved`] states the map with its least-squares rigid motion over the
//! points removed: Σᵢ‖eᵢ − (v + ω × (pᵢ − p̄))‖² minimal over (v, ω), and eᵢ less that motion.
//! This is the convention of the machine's axes as the best fit over the verified volume (the
//! volumetric error ISO 230-1 and VDI 2617-3 state relative to the part's set-up, which absorbs
//! any rigid motion); lengths between points, the length test's measurand, do not change.

use nalgebra::{DMatrix, DVector, Vector3};

/// How a map's rigid motion is stated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapGauge {
    /// As the fit gives it (its held parameters decide the rigid motion).
    AsFitted,
    /// Least-squares rigid motion over the points removed (module docs).
    RigidMotionRemoved,
}

impl MapGauge {
    /// `map` (the error at each of `points`, m) restated in this gauge.
    pub fn apply(self, points: &[Vec<f64>], map: &mut [Vector3<f64>]) {
        if self == MapGauge::RigidMotionRemoved {
            remove_rigid_motion(points, map);
        }
    }
}

/// The point `q` as a 3-vector (missing coordinates 0).
fn point(q: &[f64]) -> Vector3<f64> {
    Vector3::from_fn(|i, _| q.get(i).copied().unwrap_or(0.0))
}

/// Subtract from `map` its least-squares rigid motion over `points` (module docs). With fewer
/// than three points not on a line the rotation is not determined; the minimum-norm solution
/// (SVD) then removes what is determined.
pub fn remove_rigid_motion(points: &[Vec<f64>], map: &mut [Vector3<f64>]) {
    let n = points.len().min(map.len());
    if n == 0 {
        return;
    }
    let centre = points[..n].iter().map(|q| point(q)).sum::<Vector3<f64>>() / n as f64;
    // e ≈ v + ω × r = v − [r]× ω, r = p − p̄
    let mut a = DMatrix::zeros(3 * n, 6);
    let mut b = DVector::zeros(3 * n);
    for i in 0..n {
        let r = point(&points[i]) - centre;
        for k in 0..3 {
            a[(3 * i + k, k)] = 1.0;
            b[3 * i + k] = map[i][k];
        }
        // ω × r = (ωy rz − ωz ry, ωz rx − ωx rz, ωx ry − ωy rx)
        a[(3 * i, 4)] = r.z;
        a[(3 * i, 5)] = -r.y;
        a[(3 * i + 1, 3)] = -r.z;
        a[(3 * i + 1, 5)] = r.x;
        a[(3 * i + 2, 3)] = r.y;
        a[(3 * i + 2, 4)] = -r.x;
    }
    let Ok(x) = a.clone().svd(true, true).solve(&b, 1e-12) else {
        return;
    };
    let (v, w) = (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    );
    for i in 0..n {
        let r = point(&points[i]) - centre;
        map[i] -= v + w.cross(&r);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<Vec<f64>> {
        let mut p = vec![];
        for i in 0..4 {
            for j in 0..3 {
                for k in 0..2 {
                    p.push(vec![
                        0.8 + 0.1 * i as f64,
                        0.1 + 0.2 * j as f64,
                        0.2 * k as f64,
                    ]);
                }
            }
        }
        p
    }

    #[test]
    fn a_rigid_motion_alone_is_removed_entirely() {
        let pts = grid();
        let (v, w) = (
            Vector3::new(3e-6, -2e-6, 5e-6),
            Vector3::new(4e-5, -1e-5, 2e-5),
        );
        let mut map: Vec<Vector3<f64>> = pts.iter().map(|q| v + w.cross(&point(q))).collect();
        remove_rigid_motion(&pts, &mut map);
        assert!(map.iter().all(|e| e.norm() < 1e-15), "{map:?}");
    }

    #[test]
    fn what_is_not_rigid_is_kept_and_the_gauge_does_not_depend_on_the_rigid_part() {
        let pts = grid();
        // a scale error of X and a bow of Y: not a rigid motion
        let shape = |q: &Vec<f64>| Vector3::new(20e-6 * q[0], 30e-6 * (q[1] - 0.3).powi(2), 0.0);
        let mut plain: Vec<Vector3<f64>> = pts.iter().map(shape).collect();
        let (v, w) = (
            Vector3::new(1e-5, 0.0, -4e-6),
            Vector3::new(0.0, 3e-5, -7e-5),
        );
        let mut moved: Vec<Vector3<f64>> = pts
            .iter()
            .map(|q| shape(q) + v + w.cross(&point(q)))
            .collect();
        remove_rigid_motion(&pts, &mut plain);
        remove_rigid_motion(&pts, &mut moved);
        for (a, b) in plain.iter().zip(&moved) {
            assert!((a - b).norm() < 1e-15);
        }
        // the bow survives (its spread over Y is not a rotation)
        let spread = plain.iter().map(|e| e.y).fold(f64::MIN, f64::max)
            - plain.iter().map(|e| e.y).fold(f64::MAX, f64::min);
        assert!(spread > 1e-6, "{spread}");
    }
}
