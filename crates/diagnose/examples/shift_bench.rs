//! Benchmark: diagnosing a long recording (issue 13: an 8-hour shift bag of
//! `crates/twin/examples/cells/xfyz_shift.yaml`, without camera frames, under 60 s on 2 cores).
//! Measured in the same run, as peers: building the records from the bag (what any use of the
//! recording costs) and the declared fit alone (what `metrocell calibrate` does on it); the
//! ratios say what diagnosing adds on top.
//!
//! `crates/diagnose/bench/shift.sh` makes the bag and runs this:
//! `cargo run --release -p metrocell-diagnose --example shift_bench -- MODEL.yaml BAG...`

use std::time::Instant;

use metrocell_diagnose::{diagnose, DeclaredModel, DiagnoseOptions};
use metrocell_estimation::{fit, FitOptions};
use metrocell_records::{records_from_bags, RecordingOptions};
use metrocell_twin::CellModel;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!("usage: shift_bench MODEL.yaml BAG...");
        std::process::exit(2);
    }
    let model = CellModel::from_path(&args[0]).unwrap_or_else(|e| panic!("{e}"));
    let forward = model.forward_model().unwrap_or_else(|e| panic!("{e}"));
    let bags: Vec<&String> = args[1..].iter().collect();
    let t = Instant::now();
    let records = records_from_bags(&bags, &forward, &RecordingOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let read = t.elapsed().as_secs_f64();
    println!(
        "records from the bag: {} measurements ({} set aside) in {read:.2} s",
        records.records.len(),
        records.rejected.len()
    );
    let t = Instant::now();
    let declared_fit = fit(
        &forward,
        &model.setup,
        &records,
        None,
        &FitOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let fit_s = t.elapsed().as_secs_f64();
    println!(
        "declared fit alone: {fit_s:.2} s (χ²/dof {:.2}, {} records)",
        declared_fit.chi2_per_dof,
        records.records.len()
    );
    let declared = DeclaredModel {
        machine: &model.machine,
        machine_terms: &model.machine_terms,
        instrument_terms: &model.instrument_terms,
        setup: &model.setup,
    };
    let t = Instant::now();
    let d = diagnose(
        &declared,
        &records,
        &DiagnoseOptions {
            progress: true,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let diag = t.elapsed().as_secs_f64();
    println!(
        "diagnose: {diag:.2} s ({} records used, {} in the selection): {}",
        d.report.records.used, d.report.records.selection_records, d.report.summary
    );
    println!("bag to diagnosis: {:.2} s (target < 60 s); diagnose / records = {:.1}×, diagnose / declared fit = {:.1}×", read + diag, diag / read, diag / fit_s);
}
