//! The verification mesh: a regular grid of commanded axis positions over the volume to verify.

/// A grid from `min` to `max` on each axis at `step` (m). An axis with `min == max` is one
/// level (a plane, as the thesis's plate at one Z).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub step: f64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("the mesh step must be a positive length, got {0} m")]
    Step(f64),
    #[error("axis {axis}: the range {min} m .. {max} m is not finite or runs backwards (give min ≤ max)")]
    Range { axis: char, min: f64, max: f64 },
    #[error("axis {axis}: {min} m .. {max} m is not a whole number of {step} m steps ({n:.3}); change the range or the step")]
    NotWhole {
        axis: char,
        min: f64,
        max: f64,
        step: f64,
        n: f64,
    },
    #[error("the mesh has {0} points; more than 100 000 is not a plan a machine runs in a shift")]
    TooLarge(usize),
}

impl Mesh {
    /// The levels of each axis (m).
    pub fn levels(&self) -> Result<[Vec<f64>; 3], MeshError> {
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(MeshError::Step(self.step));
        }
        let mut out: [Vec<f64>; 3] = Default::default();
        let mut total = 1usize;
        for (a, axis) in ['x', 'y', 'z'].into_iter().enumerate() {
            let (min, max) = (self.min[a], self.max[a]);
            if !(min.is_finite() && max.is_finite() && min <= max) {
                return Err(MeshError::Range { axis, min, max });
            }
            let n = (max - min) / self.step;
            // a micrometre of slack for ranges typed in mm
            if (n - n.round()).abs() * self.step > 1e-6 {
                return Err(MeshError::NotWhole {
                    axis,
                    min,
                    max,
                    step: self.step,
                    n,
                });
            }
            let n = n.round() as usize;
            total = total.saturating_mul(n + 1);
            if total > 100_000 {
                return Err(MeshError::TooLarge(total));
            }
            out[a] = (0..=n).map(|k| min + k as f64 * self.step).collect();
        }
        Ok(out)
    }

    /// Every grid point, x fastest, then y, then z.
    pub fn points(&self) -> Result<Vec<[f64; 3]>, MeshError> {
        let [xs, ys, zs] = self.levels()?;
        let mut out = Vec::with_capacity(xs.len() * ys.len() * zs.len());
        for &z in &zs {
            for &y in &ys {
                for &x in &xs {
                    out.push([x, y, z]);
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed 001 part 2, fixture 15: X 800–1200, Y 100–500, Z 200–400 mm, step 100 → 75 points.
    #[test]
    fn the_thesis_mesh_has_75_points() {
        let m = Mesh {
            min: [0.8, 0.1, 0.2],
            max: [1.2, 0.5, 0.4],
            step: 0.1,
        };
        let p = m.points().unwrap();
        assert_eq!(p.len(), 75);
        assert_eq!(p[0], [0.8, 0.1, 0.2]);
        let last = p[74];
        assert!(
            (last[0] - 1.2).abs() < 1e-12
                && (last[1] - 0.5).abs() < 1e-12
                && (last[2] - 0.4).abs() < 1e-12
        );
    }

    #[test]
    fn a_plane_and_bad_ranges() {
        let plane = Mesh {
            min: [0.0, 0.0, 0.1],
            max: [0.4, 0.4, 0.1],
            step: 0.05,
        };
        assert_eq!(plane.points().unwrap().len(), 81);
        let odd = Mesh {
            max: [0.43, 0.4, 0.1],
            ..plane.clone()
        };
        assert!(matches!(
            odd.points(),
            Err(MeshError::NotWhole { axis: 'x', .. })
        ));
        let back = Mesh {
            min: [0.5, 0.0, 0.1],
            ..plane.clone()
        };
        assert!(matches!(
            back.points(),
            Err(MeshError::Range { axis: 'x', .. })
        ));
        let zero = Mesh { step: 0.0, ..plane };
        assert!(matches!(zero.points(), Err(MeshError::Step(_))));
    }
}
