//! A calibrated hole plate measured on the machine in the XY plane (seed 001 part 2 §1.7, the
//! PTB method of Trapet et al.; ISO 230-1 names): ring centres from four probe points, the
//! plate's misalignment and thermal expansion removed, and six error components of the XY
//! plane identified from the deviations —
//!
//! * xPx(x), yPy(y): positioning of X and of Y (cubic, zero at the plate's origin hole);
//! * xTy(x), yTx(y): straightness of X in Y and of Y in X (their linear parts belong to the
//!   alignment and the squareness, so they are quadratic and cubic only);
//! * xRz(x): yaw of X, seen as the X error growing with the distance y from the origin row
//!   (linear and quadratic in x: its constant part is the plate's own rotation);
//! * xWy: the squareness of X and Y (rad; the thesis reports mrad, its plate gave
//!   0.20448 mrad). Convention: xWy > 0 when the angle between the +X and +Y motions exceeds
//!   90° by xWy, so that, with the X motion the reference direction, a point reached by
//!   moving y along Y lies −xWy·y off in x.
//!
//! The components describe the machine's motion (where the probe is, less where it was
//! commanded), read from the plate as the negative of each ring's reported − calibrated
//! position. Error model at a plate point (x, y) from the origin hole, after the rigid alignment
//! (rotation θ, translation) that makes the X axis the reference:
//!
//!   e_x = xPx(x) + yTx(y) − y·xRz(x) − xWy·y
//!   e_y = yPy(y) + xTy(x)
//!
//! The plate measured at two heights gives each component twice; their mean cancels the
//! rotations whose Abbe arm is the height (the thesis's averaging of parallel measurements).
//! Compensation: each measured centre less the model's error there; the figure of merit is
//! the mean deviation's reduction (the thesis: 94.39 % with six components).

use nalgebra::{DMatrix, DVector, Vector2};

/// Centre of the ring through probe points (Kåsa's algebraic circle fit; four points at
/// ±X, ±Y give the midpoint of each pair for a round ring).
pub fn ring_centre(points: &[Vector2<f64>]) -> Option<Vector2<f64>> {
    if points.len() < 3 {
        return None;
    }
    let a = DMatrix::from_fn(points.len(), 3, |i, j| match j {
        0 => points[i].x,
        1 => points[i].y,
        _ => 1.0,
    });
    let b = DVector::from_fn(points.len(), |i, _| points[i].norm_squared());
    let sol = a.svd(true, true).solve(&b, 1e-12).ok()?;
    Some(Vector2::new(sol[0] / 2.0, sol[1] / 2.0))
}

/// The plate's expansion taken out of the nominal coordinates: a plate at `temperature` (°C)
/// is larger than calibrated (at 20 °C) by α(T − 20) about the clamping point (P2 eq. 2 read
/// the other way: d_f = d_0·[1 + α(T − 20)] is where the ring is at T).
pub fn expanded(
    nominal: &[Vector2<f64>],
    clamp: Vector2<f64>,
    alpha: f64,
    temperature: f64,
) -> Vec<Vector2<f64>> {
    nominal
        .iter()
        .map(|n| clamp + (n - clamp) * (1.0 + alpha * (temperature - 20.0)))
        .collect()
}

/// One measurement of the plate: the nominal (calibrated, plate frame) and measured (machine
/// frame) ring centres, m, the plate's temperature.
#[derive(Debug, Clone)]
pub struct PlateMeasurement {
    pub nominal: Vec<Vector2<f64>>,
    pub measured: Vec<Vector2<f64>>,
    pub temperature: f64,
}

/// The six components with their standard uncertainties, and how much correcting them leaves.
#[derive(Debug, Clone)]
pub struct PlateComponents {
    /// Parameter names and values (m for positions, rad for angles, per the model above) and σ.
    pub names: Vec<String>,
    pub values: Vec<f64>,
    pub sigmas: Vec<f64>,
    /// xWy (rad) and its σ.
    pub squareness: (f64, f64),
    /// Mean |deviation| of every ring of every measurement before and after correcting the
    /// six components (m), and the reduction (%).
    pub mean_before: f64,
    pub mean_after: f64,
    pub compensated_percent: f64,
    /// RMS of the residual deviations (m): the probing noise and what six components do not hold.
    pub residual_rms: f64,
}

/// The shared parameters: position and straightness coefficients (m at u = (x − x₀)/s, s the
/// plate's extent from the origin hole), the yaw's (rad per u), the squareness (rad).
const NAMES: [&str; 13] = [
    "xPx.c1", "xPx.c2", "xPx.c3", "yPy.c1", "yPy.c2", "yPy.c3", "xTy.c2", "xTy.c3", "yTx.c2",
    "yTx.c3", "xRz.c1", "xRz.c2", "xWy",
];

/// Rows of the model for a point (u, v) = (x, y)/scale from the origin hole, per measurement
/// its own alignment (θ, tx, ty) columns after the 13 shared ones.
fn rows(u: f64, v: f64, scale: f64, k: usize, count: usize) -> (Vec<f64>, Vec<f64>) {
    let n = 13 + 3 * count;
    let (mut ex, mut ey) = (vec![0.0; n], vec![0.0; n]);
    // positions (m per unit of u^k)
    ex[0] = u;
    ex[1] = u * u;
    ex[2] = u * u * u;
    ey[3] = v;
    ey[4] = v * v;
    ey[5] = v * v * v;
    ey[6] = u * u;
    ey[7] = u * u * u;
    ex[8] = v * v;
    ex[9] = v * v * v;
    // yaw of X: −y·(r1 u + r2 u²) (rad per unit)
    ex[10] = -v * scale * u;
    ex[11] = -v * scale * u * u;
    // squareness
    ex[12] = -v * scale;
    // this measurement's alignment: small rotation θ about the origin hole and a translation
    let c = 13 + 3 * k;
    ex[c] = -v * scale;
    ey[c] = u * scale;
    ex[c + 1] = 1.0;
    ey[c + 2] = 1.0;
    (ex, ey)
}

/// Identify the six components from measurements of the plate (the first nominal ring is the
/// origin), the plate's expansion about `clamp` (plate frame, m) with `alpha` removed first.
/// The constant yaw is the plate's rotation's: identifiable are the squareness and the yaw's
/// change along X, against the X axis as the reference direction.
pub fn plate_components(
    measurements: &[PlateMeasurement],
    clamp: Vector2<f64>,
    alpha: f64,
) -> Option<PlateComponents> {
    let count = measurements.len();
    let origin = measurements.first()?.nominal.first().copied()?;
    let scale = measurements
        .iter()
        .flat_map(|m| m.nominal.iter().map(|n| (n - origin).amax()))
        .fold(0.0, f64::max)
        .max(1e-9);
    let mut a_rows: Vec<Vec<f64>> = vec![];
    let mut b: Vec<f64> = vec![];
    let mut nominal_all = vec![];
    for (k, m) in measurements.iter().enumerate() {
        let at_t = expanded(&m.nominal, clamp, alpha, m.temperature);
        let o_t = at_t[0];
        for (n, p) in at_t.iter().zip(&m.measured) {
            let d = n - o_t;
            let (u, v) = (d.x / scale, d.y / scale);
            let (rx, ry) = rows(u, v, scale, k, count);
            // the machine's error there: a ring reported at d + δ (from the origin ring) is
            // where the machine stood when commanded to d + δ, so its error at d is −δ
            let dev = d - (p - m.measured[0]);
            a_rows.push(rx);
            b.push(dev.x);
            a_rows.push(ry);
            b.push(dev.y);
            nominal_all.push((k, u, v, dev));
        }
    }
    let ncol = a_rows[0].len();
    let a = DMatrix::from_fn(a_rows.len(), ncol, |i, j| a_rows[i][j]);
    let bv = DVector::from_vec(b);
    let ata = a.transpose() * &a;
    let inv = ata.clone().try_inverse()?;
    let x = &inv * a.transpose() * &bv;
    let r = &bv - &a * &x;
    let dof = (bv.len() as f64 - ncol as f64).max(1.0);
    let s2 = r.norm_squared() / dof;
    let sig: Vec<f64> = (0..ncol)
        .map(|j| (inv[(j, j)] * s2).max(0.0).sqrt())
        .collect();
    // before: deviations after the alignment alone; after: after the six components too
    let mut before = vec![];
    let mut after = vec![];
    for (k, u, v, dev) in &nominal_all {
        let (rx, ry) = rows(*u, *v, scale, *k, count);
        let c = 13 + 3 * k;
        let align = |row: &Vec<f64>| (c..c + 3).map(|j| row[j] * x[j]).sum::<f64>();
        let model = |row: &Vec<f64>| (0..13).map(|j| row[j] * x[j]).sum::<f64>();
        let aligned = Vector2::new(dev.x - align(&rx), dev.y - align(&ry));
        before.push(aligned.norm());
        after.push((aligned - Vector2::new(model(&rx), model(&ry))).norm());
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mb, ma) = (mean(&before), mean(&after));
    // the positions' coefficients are per unit of u: back to m at the plate's extent
    Some(PlateComponents {
        names: NAMES.iter().map(|s| s.to_string()).collect(),
        values: (0..13).map(|j| x[j]).collect(),
        sigmas: sig[..13].to_vec(),
        squareness: (x[12], sig[12]),
        mean_before: mb,
        mean_after: ma,
        compensated_percent: 100.0 * (1.0 - ma / mb),
        residual_rms: (r.norm_squared() / bv.len() as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_probe_points_give_the_ring_centre() {
        let c = Vector2::new(0.1234, -0.0567);
        let r = 0.0125;
        let pts: Vec<Vector2<f64>> = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
            .iter()
            .map(|(a, b)| c + Vector2::new(*a, *b) * r)
            .collect();
        let got = ring_centre(&pts).unwrap();
        assert!((got - c).norm() < 1e-12, "{got:?}");
    }

    /// Digest 001 part 1 §8.3 item 7 read as the expansion: 300 mm from the clamp at 21 °C with
    /// α = 24e-6 is 300.0072 mm (the correction back to 20 °C is the fixture's 299.9928).
    #[test]
    fn the_plate_grows_about_its_clamp() {
        let e = expanded(&[Vector2::new(0.3, 0.0)], Vector2::zeros(), 24e-6, 21.0);
        assert!((e[0].x * 1e3 - 300.0072).abs() < 1e-9);
    }
}
