//! A five-axis B/C table whose rotary axes are not where the model puts them (the catalog's
//! `rotary_axis_location`, issue 13 item 5): named first, its separable parameters within 3σ of
//! the truth, the held-out RMS back to the noise floor.

mod common;

use common::*;
use metrocell_diagnose::DiagnoseOptions;

fn cell(with_rotary_errors: bool) -> String {
    let base = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../twin/examples/cells/five_axis_table.yaml"
    ))
    .unwrap();
    // a program that turns both rotary axes: 5 tilts × 5 turns, the tip moving over the table
    let mut joints = String::from("  joints:\n");
    let mut k = 0;
    for b in [-40.0, -15.0, 0.0, 15.0, 40.0] {
        for c in [0.0, 72.0, 144.0, 216.0, 288.0] {
            let x = 420.0 + 70.0 * ((k * 3) % 5) as f64;
            let y = 430.0 + 60.0 * ((k * 2) % 5) as f64;
            let z = -320.0 + 50.0 * (k % 5) as f64;
            joints.push_str(&format!(
                "    - [{x} mm, {y} mm, {z} mm, {b} deg, {c} deg]\n"
            ));
            k += 1;
        }
    }
    let start = base.find("  poses:").unwrap();
    let end = base.find("  home_joints:").unwrap();
    let mut text = format!("{}{}{}", &base[..start], joints, &base[end..])
        .replace("cycle_interval: 60 s", "cycle_interval: 300 s");
    if with_rotary_errors {
        text.push_str("  - id: rotary_axis_location\n    options: {b_pivot: [500 mm, 500 mm, 150 mm], c_offset: [0 mm, 0 mm, 50 mm]}\n    params: {x_ob: 0 um, z_ob: 25 um, a_ob: -40 urad, c_ob: 0 urad, b_ob: 0 urad, x_oc: 30 um, y_oc: -20 um, a_oc: 50 urad, b_oc: 0 urad, c_oc: 0 urad}\n");
    }
    text
}

#[test]
fn rotary_axis_location_errors_are_named_and_fitted() {
    let hours = 40.0 / 60.0;
    let data = twin_records(
        &cell(true),
        hours,
        61,
        Take {
            moving: false,
            every: 2,
            histories: false,
        },
    );
    let d = run(&cell(false), &data.records, &DiagnoseOptions::default());
    show(&d);
    let r = &d.report;
    assert!(!r.findings.is_empty());
    let f = &r.findings[0];
    assert_eq!(
        f.label,
        "rotary_axis_location",
        "{:?}",
        r.findings.iter().map(|f| &f.label).collect::<Vec<_>>()
    );
    assert!(
        f.parameters.len() >= 4,
        "{:?}",
        f.parameters.keys().collect::<Vec<_>>()
    );
    for (name, v) in &f.parameters {
        let t = truth(&data.cell, &format!("rotary_axis_location.{name}"));
        let s = v.sigma.expect("σ");
        assert!(
            (v.value - t).abs() < 3.0 * s,
            "{name} = {:e} ± {s:e}, truth {t:e}",
            v.value
        );
    }
    assert!(
        r.after.heldout_rms_m < 1.2 * r.noise_rms_m,
        "after {:e} vs {:e}",
        r.after.heldout_rms_m,
        r.noise_rms_m
    );
}
