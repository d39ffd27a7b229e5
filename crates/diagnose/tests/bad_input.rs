//! Bad input gets a clear message and never a panic: NaN points are set aside and named, a gross
//! outlier is set aside without disturbing what is found, too few points say how many are
//! needed, and a model of another machine is refused with the reason.

mod common;

use common::*;
use metrocell_diagnose::{DiagnoseError, DiagnoseOptions};

const BACKLASH: &str = "  - id: backlash\n    options: {axis: x}\n    params: {reversal: 12 um}\n";

#[test]
fn nan_points_and_an_outlier_are_set_aside_and_the_effect_still_found() {
    let hours = 1.0;
    let truth_text = cell_yaml(BACKLASH, hours, "");
    let model_text = cell_yaml("", hours, "");
    let mut data = twin_records(&truth_text, hours, 51, Take::default());
    let n = data.records.records.len();
    data.records.records[n / 3].measured.x = f64::NAN;
    data.records.records[n / 2].covariance[(1, 1)] = f64::INFINITY;
    // a beam break that slipped through: a whole dwell 2 mm off (averaged into one record)
    let t_out = data.records.records[2 * n / 3].time;
    let q_out = data.records.records[2 * n / 3].q.clone();
    for r in data
        .records
        .records
        .iter_mut()
        .filter(|r| r.q == q_out && (r.time - t_out).abs() < 3.0)
    {
        r.measured.y += 2e-3;
    }
    let d = run(&model_text, &data.records, &DiagnoseOptions::default());
    show(&d);
    let r = &d.report;
    assert_eq!(r.records.rejected.len(), 2, "{:?}", r.records.rejected);
    assert!(
        r.records.rejected[0].contains("not finite"),
        "{:?}",
        r.records.rejected
    );
    assert_eq!(r.records.outliers.len(), 1, "{:?}", r.records.outliers);
    assert!(
        r.records.outliers[0].contains("2000") || r.records.outliers[0].contains("199"),
        "{:?}",
        r.records.outliers
    );
    assert_eq!(r.findings.len(), 1);
    assert_eq!(r.findings[0].label, "backlash[x]");
}

#[test]
fn too_few_points_say_how_many_are_needed() {
    let hours = 1.0;
    let text = cell_yaml("", hours, "");
    let mut data = twin_records(
        &text,
        hours,
        52,
        Take {
            every: 40,
            ..Take::default()
        },
    );
    data.records.records.truncate(5);
    let e = try_run(&text, &data.records, &DiagnoseOptions::default()).expect_err("an error");
    let msg = e.to_string();
    assert!(matches!(e, DiagnoseError::TooFew(_)), "{msg}");
    assert!(
        msg.contains("needs at least") && msg.contains("5 usable"),
        "{msg}"
    );
}

#[test]
fn points_on_one_side_of_the_travel_get_advice() {
    let hours = 1.0;
    let text = cell_yaml("", hours, "")
        .replace(
            "x: {from: 0 mm, to: 800 mm, count: 5}",
            "x: {from: 300 mm, to: 400 mm, count: 2}",
        )
        .replace("home: [0 mm, 0 mm, 400 mm]", "home: [300 mm, 0 mm, 400 mm]");
    let data = twin_records(&text, hours, 53, Take::default());
    let d = run(&text, &data.records, &DiagnoseOptions::default());
    assert!(
        d.report
            .messages
            .iter()
            .any(|m| m.contains("X moves over only 100 mm of its 800 mm travel")),
        "{:?}",
        d.report.messages
    );
}

#[test]
fn a_model_of_another_machine_is_refused_with_the_reason() {
    let hours = 1.0;
    let text = cell_yaml("", hours, "");
    let data = twin_records(&text, hours, 54, Take::default());
    // the same machine with a tool 50 mm longer than the recording's
    let wrong = text.replace(
        "tool_offset: [0 mm, 0 mm, -150 mm]",
        "tool_offset: [0 mm, 0 mm, -200 mm]",
    );
    let e = try_run(&wrong, &data.records, &DiagnoseOptions::default());
    // a 50 mm tool offset is a constant shift the tracker pose absorbs on a 3-axis machine: the
    // fit succeeds; a five-axis model against three joint values does not
    assert!(e.is_ok());
    let five = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../twin/examples/cells/five_axis_table.yaml"
    ))
    .unwrap();
    let e = try_run(&five, &data.records, &DiagnoseOptions::default()).expect_err("refused");
    let msg = e.to_string();
    assert!(
        msg.contains("3 joint values") && msg.contains("x y z b c"),
        "{msg}"
    );
}
