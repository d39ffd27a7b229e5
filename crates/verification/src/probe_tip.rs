//! The probe-tip check (seed 001 part 2 §1.6): a calibrated sphere measured with the head
//! turned every 15°. A tip off the spindle axis moves the measured centre round a circle once
//! per turn (first harmonic); a touch-trigger probe's kinematic three-point seating makes its
//! pretravel vary with direction, three lobes 120° apart (third harmonic). Reported as the
//! thesis's Table 5.3/5.4 (range and repeatability per axis) and as those harmonics with their
//! uncertainty, each said to be significant or not.
//!
//! Repeatability is not defined in the thesis; its figures exceed the range by about the ratio
//! a ±2σ span has to the range of a sine (4σ/2r = 1.41; Table 5.3: 0.888/0.613 = 1.45), so it
//! is taken here as 4σ of the centre positions.

use nalgebra::{DMatrix, DVector, Vector3};

/// One harmonic of the centre's motion in the XY plane: amplitude (m) and its σ, and the phase
/// (rad) of its x part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Harmonic {
    pub order: usize,
    pub amplitude: f64,
    pub sigma: f64,
    pub phase: f64,
}

impl Harmonic {
    /// Significant at 1 % false alarm: with noise alone (A/σ)² is χ² with 4 degrees of
    /// freedom, whose 99th percentile is 13.28, so A > 3.64σ.
    pub fn significant(&self) -> bool {
        self.amplitude > 3.64 * self.sigma
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ProbeTipCheck {
    /// Per axis: max − min of the centre (m) and 4σ (m).
    pub range: Vector3<f64>,
    pub repeatability: Vector3<f64>,
    /// Once per turn: the tip's distance from the spindle axis.
    pub eccentricity: Harmonic,
    /// Three per turn: the seating's lobes.
    pub three_lobe: Harmonic,
    /// Noise of a centre (m, per XY coordinate) after the harmonics 1–3.
    pub residual_sigma: f64,
}

/// Check from the sphere centres (m) measured at head angles (rad). Needs 8 or more angles.
pub fn probe_tip_check(angles: &[f64], centres: &[Vector3<f64>]) -> Option<ProbeTipCheck> {
    let n = angles.len();
    if n < 8 || centres.len() != n {
        return None;
    }
    let mut range = Vector3::zeros();
    let mut repeat = Vector3::zeros();
    for a in 0..3 {
        let v: Vec<f64> = centres.iter().map(|c| c[a]).collect();
        let (lo, hi) = v
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(*x), h.max(*x)));
        let m = v.iter().sum::<f64>() / n as f64;
        let sd = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n as f64 - 1.0)).sqrt();
        range[a] = hi - lo;
        repeat[a] = 4.0 * sd;
    }
    // x and y each: constant + cos/sin of harmonics 1, 2, 3
    let cols = 7;
    let design = DMatrix::from_fn(n, cols, |i, j| {
        let t = angles[i];
        match j {
            0 => 1.0,
            j => {
                let k = j.div_ceil(2); // columns 1, 2 → harmonic 1; 3, 4 → 2; 5, 6 → 3
                if j % 2 == 1 {
                    (k as f64 * t).cos()
                } else {
                    (k as f64 * t).sin()
                }
            }
        }
    });
    let inv = (design.transpose() * &design).try_inverse()?;
    let fit = |b: DVector<f64>| {
        let x = &inv * design.transpose() * &b;
        let r = &b - &design * &x;
        (x, r.norm_squared())
    };
    let (cx, rx) = fit(DVector::from_iterator(n, centres.iter().map(|c| c.x)));
    let (cy, ry) = fit(DVector::from_iterator(n, centres.iter().map(|c| c.y)));
    let s2 = (rx + ry) / (2.0 * (n - cols) as f64).max(1.0);
    let harmonic = |k: usize| {
        let (c, s) = (2 * k - 1, 2 * k);
        // the centre's motion at k per turn, turning with the head (a bent tip) or against it
        // (lobes probed from fixed directions): as a circle of radius A, Σ coefficients² = 2A²
        let sum = cx[c].powi(2) + cx[s].powi(2) + cy[c].powi(2) + cy[s].powi(2);
        let amplitude = (sum / 2.0).sqrt();
        // each coefficient's variance v = s2·inv (2s2/n for even spacing); A's is v/2
        let v = s2 * (inv[(c, c)] + inv[(s, s)]) / 2.0;
        Harmonic {
            order: k,
            amplitude,
            sigma: (v / 2.0).sqrt(),
            phase: cx[s].atan2(cx[c]),
        }
    };
    Some(ProbeTipCheck {
        range,
        repeatability: repeat,
        eccentricity: harmonic(1),
        three_lobe: harmonic(3),
        residual_sigma: s2.sqrt(),
    })
}
