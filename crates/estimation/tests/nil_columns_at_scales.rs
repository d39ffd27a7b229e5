//! Issue 32 item 5: a time constant (s) beside a probe's pretravel (m) was held as "no
//! measurement depends on it" — per unit parameter its column is 10⁻¹⁰ of the pretravel's. The
//! nil test compares effects over each parameter's typical change, so it is not.

use metrocell_estimation::fit::{inseparable, inseparable_at_scales};
use nalgebra::DMatrix;

#[test]
fn a_small_unit_column_is_nil_only_per_unit() {
    // rows: a pretravel column (1e6 per m) and a time-constant column (1e-4 per s), independent
    let mut j = DMatrix::zeros(4, 2);
    j[(0, 0)] = 1e6;
    j[(1, 0)] = 1e6;
    j[(2, 1)] = 1e-4;
    j[(3, 1)] = -1e-4;
    let names = vec![
        "probe_pretravel.p0".to_string(),
        "tracker_warmup.time_constant".to_string(),
    ];
    let per_unit = inseparable(&j, &[0, 1], &names);
    assert_eq!(
        per_unit.len(),
        1,
        "per unit the time constant looks nil: {per_unit:?}"
    );
    // typical changes: 10 µm of pretravel, 3 h of time constant
    let held = inseparable_at_scales(&j, &[0, 1], &names, Some(&[10e-6, 3.0 * 3600.0]));
    assert!(
        held.is_empty(),
        "at their typical sizes both are measured: {held:?}"
    );
    // a truly nil column stays nil at any scale
    j[(2, 1)] = 0.0;
    j[(3, 1)] = 0.0;
    let held = inseparable_at_scales(&j, &[0, 1], &names, Some(&[10e-6, 3.0 * 3600.0]));
    assert_eq!(held.len(), 1);
    assert!(held[0].1.contains("no measurement depends on it"));
}
