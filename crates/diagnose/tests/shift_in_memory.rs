//! How long a long shift takes, in memory (a development probe; the benchmark runs the command
//! on a `metrocell sim` bag): `SHIFT_HOURS=8 cargo test -p metrocell-diagnose --test
//! shift_in_memory -- --ignored --nocapture`.

mod common;

use common::*;
use metrocell_diagnose::DiagnoseOptions;

#[test]
#[ignore = "performance probe; minutes"]
fn shift_in_memory() {
    let hours: f64 = std::env::var("SHIFT_HOURS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    let base = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../twin/examples/cells/xfyz_shift.yaml"
    ))
    .unwrap();
    let start = base.find("  camera:").unwrap();
    let end = base.find("environment:").unwrap();
    let truth = format!("{}{}", &base[..start], &base[end..]);
    let model = truth.replace(
        "  - id: backlash\n    options: {axis: x}\n    params: {reversal: 8 um}\n",
        "",
    );
    assert_ne!(model, truth);
    let t0 = std::time::Instant::now();
    let data = twin_records(
        &truth,
        hours,
        1,
        Take {
            moving: true,
            every: 1,
            histories: true,
        },
    );
    eprintln!(
        "{} readings made in {:.1} s",
        data.records.records.len(),
        t0.elapsed().as_secs_f64()
    );
    let t1 = std::time::Instant::now();
    let d = run(
        &model,
        &data.records,
        &DiagnoseOptions {
            progress: true,
            ..Default::default()
        },
    );
    eprintln!("diagnosed in {:.1} s", t1.elapsed().as_secs_f64());
    show(&d);
    // the one concealed term (the 8 µm X reversal) is what it names first, within 3σ
    let first = d
        .report
        .findings
        .first()
        .expect("nothing named: the concealed backlash[x] was missed");
    assert_eq!(
        first.label,
        "backlash[x]",
        "{:?}",
        d.report
            .findings
            .iter()
            .map(|f| &f.label)
            .collect::<Vec<_>>()
    );
    let v = &first.parameters["reversal"];
    let s = v.sigma.expect("σ of the reversal");
    assert!(
        (v.value - 8e-6).abs() <= 3.0 * s,
        "backlash[x].reversal = {:e} ± {s:e}, truth 8e-6",
        v.value
    );
}
