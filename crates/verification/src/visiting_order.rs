//! The order the machine visits the mesh, and how it arrives at each point.
//!
//! Order: Z layers from the lowest up; within a layer a spiral over the grid, from the outer
//! ring inwards (the thesis visits its plate's holes "in a spiral", P2, because its simulations
//! showed less backlash effect that way).
//!
//! Approach: every point is reached by a last move of `approach` in + on every axis, from
//! `point − approach·(1, 1, 1)`. An axis's backlash (lost motion on reversal) then leaves the
//! carriage on the same side of its play at every point: the error is one constant per axis,
//! which the registration's origin takes, and none of it enters the error map. ISO 230-2 calls
//! this a unidirectional approach. The approach must exceed the largest backlash expected.

/// Indices into `points` in visiting order. `points` must be a grid (as [`crate::Mesh::points`]
/// gives): they are grouped by Z level, and each level's X and Y levels index the spiral.
pub fn spiral_order(points: &[[f64; 3]]) -> Vec<usize> {
    let key = |v: f64| (v * 1e6).round() as i64; // µm: grid levels typed in mm compare exactly
    let mut zs: Vec<i64> = points.iter().map(|p| key(p[2])).collect();
    zs.sort_unstable();
    zs.dedup();
    let mut order = Vec::with_capacity(points.len());
    for z in zs {
        let layer: Vec<usize> = (0..points.len())
            .filter(|&i| key(points[i][2]) == z)
            .collect();
        let mut xs: Vec<i64> = layer.iter().map(|&i| key(points[i][0])).collect();
        let mut ys: Vec<i64> = layer.iter().map(|&i| key(points[i][1])).collect();
        xs.sort_unstable();
        xs.dedup();
        ys.sort_unstable();
        ys.dedup();
        let at = |ix: usize, iy: usize| {
            layer
                .iter()
                .copied()
                .find(|&i| key(points[i][0]) == xs[ix] && key(points[i][1]) == ys[iy])
        };
        let (mut left, mut right, mut bottom, mut top) =
            (0i64, xs.len() as i64 - 1, 0i64, ys.len() as i64 - 1);
        let mut ring = Vec::new();
        while left <= right && bottom <= top {
            for ix in left..=right {
                ring.push((ix, bottom));
            }
            for iy in bottom + 1..=top {
                ring.push((right, iy));
            }
            if bottom < top {
                for ix in (left..right).rev() {
                    ring.push((ix, top));
                }
            }
            if left < right {
                for iy in (bottom + 1..top).rev() {
                    ring.push((left, iy));
                }
            }
            left += 1;
            right -= 1;
            bottom += 1;
            top -= 1;
        }
        // a layer that is not a full grid still visits each of its points once
        let mut seen = vec![false; points.len()];
        for (ix, iy) in ring {
            if let Some(i) = at(ix as usize, iy as usize) {
                if !seen[i] {
                    seen[i] = true;
                    order.push(i);
                }
            }
        }
        order.extend(layer.into_iter().filter(|&i| !seen[i]));
    }
    order
}

/// Where the last move to `point` starts: `approach` below it on every axis.
pub fn approach_start(point: [f64; 3], approach: f64) -> [f64; 3] {
    [
        point[0] - approach,
        point[1] - approach,
        point[2] - approach,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;

    /// An axis with lost motion: the carriage lags the command within a play of `backlash`
    /// (it stays put until the command has taken up the play), the hysteresis a reversal shows.
    struct PlayAxis {
        half: f64,
        at: f64,
    }
    impl PlayAxis {
        fn command(&mut self, c: f64) -> f64 {
            self.at = self.at.clamp(c - self.half, c + self.half);
            self.at
        }
    }

    /// The carriage's error (reached − commanded) at each point of a route, per axis, for a
    /// machine whose axes have `backlash`.
    fn errors_along(route: &[([f64; 3], bool)], backlash: f64) -> Vec<[f64; 3]> {
        let mut axes: Vec<PlayAxis> = (0..3)
            .map(|_| PlayAxis {
                half: backlash / 2.0,
                at: 0.0,
            })
            .collect();
        let mut out = vec![];
        for (p, measured) in route {
            let reached: Vec<f64> = (0..3).map(|a| axes[a].command(p[a])).collect();
            if *measured {
                out.push([reached[0] - p[0], reached[1] - p[1], reached[2] - p[2]]);
            }
        }
        out
    }

    fn spread(e: &[[f64; 3]]) -> f64 {
        (0..3)
            .map(|a| {
                let v = e.iter().map(|x| x[a]);
                v.clone().fold(f64::MIN, f64::max) - v.fold(f64::MAX, f64::min)
            })
            .fold(0.0, f64::max)
    }

    /// The thesis's claim that its route keeps backlash below 1 µm, checked with a play model:
    /// with the unidirectional approach every point carries the same offset on every axis (the
    /// spread is 0 for 20 µm of backlash), without it the spiral reverses the axes and the
    /// spread is the whole backlash.
    #[test]
    fn the_unidirectional_approach_leaves_backlash_as_one_constant() {
        let mesh = Mesh {
            min: [0.0, 0.0, 0.0],
            max: [0.4, 0.4, 0.2],
            step: 0.1,
        };
        let pts = mesh.points().unwrap();
        let order = spiral_order(&pts);
        let backlash = 20e-6;
        let mut with = vec![];
        for &i in &order {
            with.push((approach_start(pts[i], 2e-3), false));
            with.push((pts[i], true));
        }
        let e = errors_along(&with, backlash);
        assert!(spread(&e) < 1e-9, "spread {:e}", spread(&e));
        assert!(
            (e[0][0] + backlash / 2.0).abs() < 1e-12,
            "the carriage lags by half the play: {:?}",
            e[0]
        );
        let without: Vec<_> = order.iter().map(|&i| (pts[i], true)).collect();
        let e = errors_along(&without, backlash);
        assert!(
            (spread(&e) - backlash).abs() < 1e-12,
            "spread {:e}",
            spread(&e)
        );
    }

    #[test]
    fn the_spiral_visits_every_point_once_layer_by_layer_from_the_outside_in() {
        let mesh = Mesh {
            min: [0.0, 0.0, 0.0],
            max: [0.3, 0.2, 0.1],
            step: 0.1,
        };
        let pts = mesh.points().unwrap();
        let order = spiral_order(&pts);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..pts.len()).collect::<Vec<_>>());
        // 4 × 3 per layer: the ring of 10, then the 2 inside; the lower layer first
        assert!(order[..12].iter().all(|&i| pts[i][2] == 0.0));
        let first_layer: Vec<[f64; 3]> = order[..12].iter().map(|&i| pts[i]).collect();
        let ring = &first_layer[..10];
        assert!(ring
            .iter()
            .all(|p| p[0] == 0.0 || p[0] > 0.29 || p[1] == 0.0 || p[1] > 0.19));
        assert!(first_layer[10..]
            .iter()
            .all(|p| (p[1] - 0.1).abs() < 1e-9 && p[0] > 0.05 && p[0] < 0.25));
        // consecutive ring points are neighbours (one step apart)
        for w in ring.windows(2) {
            let d = ((w[0][0] - w[1][0]).powi(2) + (w[0][1] - w[1][1]).powi(2)).sqrt();
            assert!((d - 0.1).abs() < 1e-9, "{w:?}");
        }
    }
}
