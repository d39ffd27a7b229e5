//! Single concealed effects in records the twin made (in memory): the right term is named
//! first, its parameters lie within 3σ of the truth, and the held-out RMS after is within 1.2×
//! the noise floor; a complete model names nothing.

mod common;

use common::*;
use metrocell_diagnose::DiagnoseOptions;

const BACKLASH: &str = "  - id: backlash\n    options: {axis: x}\n    params: {reversal: 12 um}\n";

#[test]
fn concealed_backlash_is_named_with_its_value() {
    let hours = 2.0;
    let truth_text = cell_yaml(BACKLASH, hours, "");
    let model_text = cell_yaml("", hours, "");
    let data = twin_records(&truth_text, hours, 11, Take::default());
    let d = run(&model_text, &data.records, &DiagnoseOptions::default());
    show(&d);
    let r = &d.report;
    assert!(!r.findings.is_empty(), "nothing found");
    let f = &r.findings[0];
    assert_eq!(f.label, "backlash[x]");
    let p = &f.parameters["reversal"];
    let truth = truth(&data.cell, "backlash[x].reversal");
    let sigma = p.sigma.unwrap();
    assert!((p.value - truth).abs() < 3.0 * sigma, "β = {} ± {sigma}, truth {truth}", p.value);
    assert_eq!(r.findings.len(), 1, "{:?}", r.findings.iter().map(|f| &f.label).collect::<Vec<_>>());
    assert!(r.after.heldout_rms_m < 1.2 * r.noise_rms_m, "held-out RMS after {} vs noise {}", r.after.heldout_rms_m, r.noise_rms_m);
    assert!(r.before.heldout_rms_m > r.after.heldout_rms_m);
    assert!(r.explained, "{:?}", r.remaining);
}

#[test]
fn complete_model_names_nothing() {
    let hours = 2.0;
    let truth_text = cell_yaml(BACKLASH, hours, "");
    let data = twin_records(&truth_text, hours, 12, Take::default());
    let d = run(&truth_text, &data.records, &DiagnoseOptions::default());
    show(&d);
    assert!(d.report.findings.is_empty(), "{:?}", d.report.findings.iter().map(|f| &f.label).collect::<Vec<_>>());
    assert!(d.report.unexplained.is_empty());
}
