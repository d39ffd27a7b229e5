//! Per-axis compensation tables a CNC controller loads (pitch, straightness, reversal per
//! axis, squareness per axis pair), sampled from an error field, and their CSV layout.
//!
//! Layout (one file per axis, `axis_x.csv` …, and `squareness.csv`), documented here once:
//! ```text
//! # metrocell compensation table: axis x of MODEL (…), other axes at y = 250.000 mm, z = 200.000 mm
//! # values are errors, reached − commanded (µm) at the commanded position; a controller
//! # compensates by commanding position − error (most controllers' "compensation value" = −error)
//! position_mm,pitch_um,straightness_y_um,straightness_z_um,reversal_um
//! 0.000,1.234,-0.512,0.044,8.000
//! ```
//! * `pitch` — the error along the axis itself (ISO 230-1 E_XX) approaching in +;
//! * `straightness_<d>` — the errors across it (E_YX, E_ZX), approaching in +, as measured
//!   (their least-squares slope is included: the squareness file gives that slope's share);
//! * `reversal` — error approaching in − minus approaching in + along the axis (what backlash
//!   compensation adds on a reversal).
//!
//! `squareness.csv`: `pair,squareness_urad` for xy, xz, yz, from the least-squares lines of the
//! straightness columns: s_ab = −(slope of a's error along b as b moves + slope of b's error
//! along a as a moves), the catalog's sign (`squareness` term: d = (−y·s, 0, 0) for xy), so a
//! pure frame rotation gives 0.

use nalgebra::Vector3;

use crate::error_field::{ErrorField, FieldError, Region};

const AXES: [&str; 3] = ["x", "y", "z"];

/// The samples of one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisTable {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Commanded positions along the axis, m (the other axes at the reference).
    pub positions: Vec<f64>,
    /// Error vector approaching in +, m.
    pub errors: Vec<Vector3<f64>>,
    /// Error along the axis approaching in − minus approaching in +, m.
    pub reversal: Vec<f64>,
    /// The other axes' positions, m.
    pub reference: Vector3<f64>,
}

/// Sample every axis across `region` at `step` (m; the last point is the travel's end), the
/// other axes at `reference`.
pub fn axis_tables(
    field: &dyn ErrorField,
    region: &Region,
    reference: &Vector3<f64>,
    step: f64,
) -> Result<Vec<AxisTable>, FieldError> {
    if !(step > 0.0 && step.is_finite()) {
        return Err(FieldError(format!("table step must be > 0, got {step} m")));
    }
    let mut out = Vec::new();
    for a in 0..3 {
        let (lo, hi) = (region.min[a], region.max[a]);
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(FieldError(format!(
                "axis {} has no finite travel to tabulate ([{lo}, {hi}] m)",
                AXES[a]
            )));
        }
        let n = ((hi - lo) / step).ceil() as usize;
        let positions: Vec<f64> = (0..=n).map(|k| (lo + k as f64 * step).min(hi)).collect();
        let mut errors = Vec::new();
        let mut reversal = Vec::new();
        for &p in &positions {
            let mut c = *reference;
            c[a] = p;
            let forward = field.error(&c, &[1.0; 3])?;
            let mut back_dir = [1.0; 3];
            back_dir[a] = -1.0;
            let back = field.error(&c, &back_dir)?;
            errors.push(forward);
            reversal.push(back[a] - forward[a]);
        }
        out.push(AxisTable {
            axis: a,
            positions,
            errors,
            reversal,
            reference: *reference,
        });
    }
    Ok(out)
}

/// `v` to three decimals without a negative zero.
fn fixed3(v: f64) -> String {
    format!("{:.3}", (v * 1e3).round() / 1e3 + 0.0)
}

/// Least-squares slope of `y` over `x`.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

/// Squareness of xy, xz, yz (rad, catalog sign) from the tables' straightness lines.
pub fn squareness(tables: &[AxisTable]) -> Vec<(String, f64)> {
    let by = |a: usize| tables.iter().find(|t| t.axis == a);
    let mut out = Vec::new();
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        if let (Some(ta), Some(tb)) = (by(a), by(b)) {
            // a's error as b moves, and b's error as a moves
            let m_b_to_a = slope(
                &tb.positions,
                &tb.errors.iter().map(|e| e[a]).collect::<Vec<_>>(),
            );
            let m_a_to_b = slope(
                &ta.positions,
                &ta.errors.iter().map(|e| e[b]).collect::<Vec<_>>(),
            );
            out.push((format!("{}{}", AXES[a], AXES[b]), -(m_b_to_a + m_a_to_b)));
        }
    }
    out
}

/// One axis table as CSV (µm, mm), with `title` in the first comment line.
pub fn axis_csv(t: &AxisTable, title: &str) -> String {
    let others: Vec<usize> = (0..3).filter(|&k| k != t.axis).collect();
    let mut s = format!(
        "# metrocell compensation table: axis {} of {title}, other axes at {} = {:.3} mm, {} = {:.3} mm\n# values are errors, reached − commanded (µm) at the commanded position; a controller\n# compensates by commanding position − error (most controllers' \"compensation value\" = −error)\n",
        AXES[t.axis], AXES[others[0]], t.reference[others[0]] * 1e3, AXES[others[1]], t.reference[others[1]] * 1e3
    );
    s += &format!(
        "position_mm,pitch_um,straightness_{}_um,straightness_{}_um,reversal_um\n",
        AXES[others[0]], AXES[others[1]]
    );
    for ((p, e), r) in t.positions.iter().zip(&t.errors).zip(&t.reversal) {
        s += &format!(
            "{},{},{},{},{}\n",
            fixed3(p * 1e3),
            fixed3(e[t.axis] * 1e6),
            fixed3(e[others[0]] * 1e6),
            fixed3(e[others[1]] * 1e6),
            fixed3(r * 1e6)
        );
    }
    s
}

/// The squareness file as CSV (µrad).
pub fn squareness_csv(values: &[(String, f64)], title: &str) -> String {
    let mut s = format!("# metrocell squareness of {title}: from the least-squares lines of the axis tables' straightness, the catalog's sign (xy: d = (−y·s, 0, 0))\npair,squareness_urad\n");
    for (pair, v) in values {
        s += &format!("{pair},{}\n", fixed3(v * 1e6));
    }
    s
}
