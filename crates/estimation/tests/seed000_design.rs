//! Seed 000's design question (digest T7, T10): 12 measurement rows chosen from the 36-point
//! grid's x and y rows for the planar error field of eq. 7 must beat any of 1000 random 12-row
//! designs on det(XᵀX).

use metrocell_estimation::design_of_experiments::{best_random_log_det, d_optimal};
use nalgebra::DMatrix;

/// Rows of eq. 7's nine coefficients (A..I) at the 6 × 6 grid (25 mm pitch, centres 12.5 …
/// 137.5 mm, X3 = 1): an e_x row and an e_y row per point, coordinates in units of 100 mm so the
/// columns are of similar size.
fn eq7_candidates() -> DMatrix<f64> {
    let centres: Vec<f64> = (0..6).map(|k| (12.5 + 25.0 * k as f64) / 100.0).collect();
    let mut rows = Vec::new();
    for &x1 in &centres {
        for &x2 in &centres {
            rows.push([x2 * x2, x2, x1, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
            rows.push([0.0, 0.0, 0.0, 0.0, x1, x2, 1.0, x1 * x2, x1 * x1]);
        }
    }
    DMatrix::from_fn(rows.len(), 9, |i, k| rows[i][k])
}

#[test]
fn twelve_row_design_beats_random_designs() {
    let c = eq7_candidates();
    assert_eq!(
        c.nrows(),
        72,
        "36 points × 2 directions (seed 000's B72 rows)"
    );
    let design = d_optimal(&c, 12, 5, 2026).unwrap();
    assert_eq!(design.rows.len(), 12);
    assert_eq!(
        design.rank, 9,
        "eq. 7 has nine coefficients, all identifiable from 12 good rows"
    );
    let best_random = best_random_log_det(&c, 12, 1000, 7);
    assert!(
        design.log_det >= best_random,
        "design ln det {} < best of 1000 random {best_random}",
        design.log_det
    );
    // and by a clear margin: the random designs are far from optimal
    assert!(
        design.log_det - best_random > 0.5,
        "margin {}",
        design.log_det - best_random
    );
}
