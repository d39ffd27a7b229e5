//! Empirical corrections: smooth functions with no physical name, for structure no catalog term
//! explains — a correction of the measured point along one workpiece axis that varies smoothly
//! in time (a uniform cubic B-spline over the recording), or a local bump over the workspace (a
//! Gaussian of the commanded position). They are fitted, scored and reported like candidate
//! terms, labelled `empirical`, and never enter the model file as physics.

use nalgebra::Vector3;
use serde::Serialize;

/// The shape of an empirical correction along workpiece axis `axis`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EmpiricalShape {
    /// Σ_j c_j·B_j(t): `knots` uniform cubic B-splines over [start, end] (s).
    TimeSpline { start: f64, end: f64, knots: usize },
    /// c·exp(−|p − centre|²/(2·width²)), p the commanded position (m).
    WorkspaceBump { centre: [f64; 3], width: f64 },
}

/// An empirical correction as fitted: its basis, coefficients, their σ, and its net effect on
/// the records along its axis (m).
pub type FittedEmpirical = (EmpiricalBasis, Vec<f64>, Vec<f64>, Vec<f64>);

/// One empirical correction: its shape and the workpiece axis it moves.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EmpiricalBasis {
    pub axis: usize,
    #[serde(flatten)]
    pub shape: EmpiricalShape,
    /// The basis functions in use (the others are spanned by the declared model's parameters —
    /// a spline's constant is the instrument's position — and left out); None: all.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kept: Option<Vec<usize>>,
    /// How many centres the bump's was chosen among (1 for a spline).
    #[serde(skip)]
    pub centres_tried: usize,
}

/// The cardinal cubic B-spline on [0, 4].
fn cubic_b(x: f64) -> f64 {
    if !(0.0..4.0).contains(&x) {
        0.0
    } else if x < 1.0 {
        x * x * x / 6.0
    } else if x < 2.0 {
        (-3.0 * x * x * x + 12.0 * x * x - 12.0 * x + 4.0) / 6.0
    } else if x < 3.0 {
        (3.0 * x * x * x - 24.0 * x * x + 60.0 * x - 44.0) / 6.0
    } else {
        (4.0 - x).powi(3) / 6.0
    }
}

impl EmpiricalBasis {
    /// Number of basis functions of the shape.
    fn full_len(&self) -> usize {
        match self.shape {
            EmpiricalShape::TimeSpline { knots, .. } => knots,
            EmpiricalShape::WorkspaceBump { .. } => 1,
        }
    }

    /// Number of coefficients (basis functions in use).
    pub fn len(&self) -> usize {
        self.kept
            .as_ref()
            .map(|k| k.len())
            .unwrap_or_else(|| self.full_len())
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Shape parameters chosen by search (counted by the information criterion).
    pub fn searched(&self) -> usize {
        match self.shape {
            EmpiricalShape::TimeSpline { .. } => 0,
            EmpiricalShape::WorkspaceBump { .. } => 4,
        }
    }

    /// Effectively different shapes compared to choose this one: the centres a bump was tried
    /// at (see [`crate::selection::Variant::search_multiplicity`]); 1 for a spline.
    pub fn search_multiplicity(&self) -> f64 {
        match self.shape {
            EmpiricalShape::TimeSpline { .. } => 1.0,
            EmpiricalShape::WorkspaceBump { .. } => self.centres_tried as f64,
        }
    }

    /// The basis values at time t and commanded position p (one per coefficient).
    pub fn values(&self, t: f64, p: &Vector3<f64>) -> Vec<f64> {
        let all = self.all_values(t, p);
        match &self.kept {
            Some(k) => k.iter().map(|&j| all[j]).collect(),
            None => all,
        }
    }

    fn all_values(&self, t: f64, p: &Vector3<f64>) -> Vec<f64> {
        match self.shape {
            EmpiricalShape::TimeSpline { start, end, knots } => {
                let h = (end - start) / (knots - 3) as f64;
                let u = ((t - start) / h).clamp(0.0, (knots - 3) as f64 - 1e-12);
                (0..knots).map(|j| cubic_b(u - j as f64 + 3.0)).collect()
            }
            EmpiricalShape::WorkspaceBump { centre, width } => {
                let d = p - Vector3::from(centre);
                vec![(-d.norm_squared() / (2.0 * width * width)).exp()]
            }
        }
    }

    /// The correction (m, along the axis) for coefficients `c`.
    pub fn value(&self, c: &[f64], t: f64, p: &Vector3<f64>) -> f64 {
        self.values(t, p).iter().zip(c).map(|(a, b)| a * b).sum()
    }

    /// A short name: `empirical_time[z] (16 knots)`, `empirical_bump[x]`.
    pub fn label(&self) -> String {
        let axis = crate::residual::axis_name(self.axis);
        match self.shape {
            EmpiricalShape::TimeSpline { .. } => format!("empirical_time[{axis}]"),
            EmpiricalShape::WorkspaceBump { .. } => format!("empirical_bump[{axis}]"),
        }
    }

    pub fn variant_name(&self) -> String {
        match self.shape {
            EmpiricalShape::TimeSpline { knots, .. } => format!("{knots} knots"),
            EmpiricalShape::WorkspaceBump { centre, width } => format!(
                "centre ({:.0}, {:.0}, {:.0}) mm, width {:.0} mm",
                centre[0] * 1e3,
                centre[1] * 1e3,
                centre[2] * 1e3,
                width * 1e3
            ),
        }
    }
}

/// Time-spline variants for each axis: knot counts that leave at least 8 records per knot.
pub fn time_variants(times: &[f64], axis: usize) -> Vec<EmpiricalBasis> {
    let (t0, t1) = times
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    if !(t1 > t0) {
        return Vec::new();
    }
    [4usize, 6, 10, 16, 24, 32]
        .into_iter()
        .filter(|k| times.len() >= 8 * k)
        .map(|knots| EmpiricalBasis {
            axis,
            shape: EmpiricalShape::TimeSpline {
                start: t0,
                end: t1,
                knots,
            },
            kept: None,
            centres_tried: 1,
        })
        .collect()
}

/// Bump variants for each axis: for widths of 5, 8, 12, 18 and 25 % of the workspace diagonal, the
/// centre where the kernel-smoothed residual along the axis stands out most (smoothed mean ×
/// √(kernel weight), so a lone point does not win).
pub fn bump_variants(
    positions: &[Vector3<f64>],
    residual: &[f64],
    weight: &[f64],
    axis: usize,
) -> Vec<EmpiricalBasis> {
    let n = positions.len();
    if n < 12 {
        return Vec::new();
    }
    let (lo, hi) = positions.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(a, b), p| (a.inf(p), b.sup(p)),
    );
    let diagonal = (hi - lo).norm();
    if !(diagonal > 0.0) {
        return Vec::new();
    }
    let stride = n.div_ceil(400);
    let centres: Vec<Vector3<f64>> = positions.iter().step_by(stride).copied().collect();
    let mut out = Vec::new();
    for fraction in [0.05, 0.08, 0.12, 0.18, 0.25] {
        let width = fraction * diagonal;
        let mut best: Option<(f64, Vector3<f64>)> = None;
        for c in &centres {
            let (mut sw, mut swr, mut sw2) = (0.0, 0.0, 0.0);
            for i in 0..n {
                let k =
                    (-(positions[i] - c).norm_squared() / (2.0 * width * width)).exp() * weight[i];
                sw += k;
                swr += k * residual[i];
                sw2 += k * k / weight[i].max(f64::MIN_POSITIVE);
            }
            if sw <= 0.0 {
                continue;
            }
            // the kernel-weighted mean in units of its standard error
            let stat = (swr / sw).abs() * sw / sw2.sqrt().max(f64::MIN_POSITIVE);
            if best.is_none_or(|(b, _)| stat > b) {
                best = Some((stat, *c));
            }
        }
        if let Some((_, c)) = best {
            out.push(EmpiricalBasis {
                axis,
                shape: EmpiricalShape::WorkspaceBump {
                    centre: [c.x, c.y, c.z],
                    width,
                },
                kept: None,
                centres_tried: centres.len(),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splines_partition_unity_and_bumps_peak_at_their_centre() {
        let b = EmpiricalBasis {
            axis: 2,
            shape: EmpiricalShape::TimeSpline {
                start: 10.0,
                end: 70.0,
                knots: 7,
            },
            kept: None,
            centres_tried: 1,
        };
        for t in [10.0, 23.3, 55.0, 70.0] {
            let v = b.values(t, &Vector3::zeros());
            assert_eq!(v.len(), 7);
            assert!((v.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{t}: {v:?}");
        }
        let positions: Vec<Vector3<f64>> = (0..400)
            .map(|i| Vector3::new((i % 20) as f64 * 0.04, (i / 20) as f64 * 0.03, 0.1))
            .collect();
        let centre = Vector3::new(0.52, 0.33, 0.1);
        let residual: Vec<f64> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                10.0 * (-(p - centre).norm_squared() / (2.0 * 0.06f64.powi(2))).exp()
                    + ((i * 13) % 7) as f64 / 7.0
                    - 0.5
            })
            .collect();
        let v = bump_variants(&positions, &residual, &vec![1.0; 400], 0);
        let EmpiricalShape::WorkspaceBump { centre: c, .. } = v[0].shape else {
            panic!()
        };
        assert!((Vector3::from(c) - centre).norm() < 0.05, "{c:?}");
    }
}
