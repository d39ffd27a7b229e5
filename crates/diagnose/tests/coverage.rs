//! The found terms' σ cover the truth at their stated rate when the residuals are correlated in
//! time (issue 13): over many seeds of a one-hour twin recording with a concealed 10 µm X
//! reversal error and a drift no model term holds (AR(1) in time, 1 µm per axis, correlated
//! over a minute — a tracker's wander, air moving on the beam), the reversal is reported in most
//! runs and, where reported, lies within 1σ of the truth in about 68 % of them and within 2σ in
//! about 95 %. The rates are counted over ALL runs: a run that does not report the reversal the
//! recording holds is a miss (reported separately, and bounded), and it covers nothing. Asserted,
//! of all runs: at most MAX_MISS_RATE misses; the truth within 1σ in at least MIN_WITHIN_1 and at
//! most 0.9 (not grossly over-conservative), within 2σ in at least MIN_WITHIN_2 — the nominal
//! 0.68 and 0.95 times the runs expected to report it (about 3 in 4): 0.51 and 0.71, less three
//! binomial standard deviations of the default 24 runs (0.10 and 0.09): 0.20 and 0.43. The log
//! also gives the rates the independent-rows σ would have had.
//!
//! `METROCELL_COVERAGE_SEEDS` sets the number of runs (default 24, about 30 s with the
//! workspace's optimised test profile; BENCHMARKS.md quotes a longer run):
//! `METROCELL_COVERAGE_SEEDS=100 cargo test --release -p metrocell-diagnose --test coverage -- --nocapture`.

mod common;

use common::*;
use metrocell_diagnose::DiagnoseOptions;
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const CONCEALED: &str = "  - id: backlash\n    options: {axis: x}\n    params: {reversal: 10 um}\n";
const LABEL: &str = "backlash[x]";
const PARAM: &str = "reversal";

/// Correlation time of the drift (s) and its standard deviation per axis (m).
const DRIFT_TAU: f64 = 60.0;
const DRIFT_SIGMA: f64 = 1.0e-6;

/// What is asserted of all runs (module doc): the largest share of runs that may miss the
/// reversal, and the least shares with the truth within 1σ and 2σ of the reported value.
const MAX_MISS_RATE: f64 = 0.4;
const MIN_WITHIN_1: f64 = 0.20;
const MIN_WITHIN_2: f64 = 0.43;

fn seeds() -> u64 {
    std::env::var("METROCELL_COVERAGE_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(24)
}

/// An AR(1) drift per workpiece axis sampled at `times` (sorted), stationary from the start.
fn drift(times: &[f64], seed: u64) -> Vec<Vector3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_d41f);
    // Box–Muller
    let mut normal = || -> f64 {
        (-2.0 * (1.0 - rng.random::<f64>()).ln()).sqrt()
            * (std::f64::consts::TAU * rng.random::<f64>()).cos()
    };
    let mut z = Vector3::new(normal(), normal(), normal()) * DRIFT_SIGMA;
    let mut last = times.first().copied().unwrap_or(0.0);
    times
        .iter()
        .map(|&t| {
            let phi = (-(t - last).max(0.0) / DRIFT_TAU).exp();
            let keep = (1.0 - phi * phi).sqrt() * DRIFT_SIGMA;
            z = z * phi + Vector3::new(normal(), normal(), normal()) * keep;
            last = t;
            z
        })
        .collect()
}

#[test]
fn found_sigma_covers_the_truth_with_correlated_residuals() {
    let hours = 1.0;
    let truth_text = cell_yaml(CONCEALED, hours, "");
    let model_text = cell_yaml("", hours, "");
    let n = seeds();
    let (mut within1, mut within2, mut found) = (0usize, 0usize, 0usize);
    let (mut classical1, mut classical2) = (0usize, 0usize);
    let mut z_scores = Vec::new();
    let started = std::time::Instant::now();
    for seed in 0..n {
        let mut data = twin_records(
            &truth_text,
            hours,
            1000 + seed,
            Take {
                every: 3,
                ..Take::default()
            },
        );
        let times: Vec<f64> = data.records.records.iter().map(|r| r.time).collect();
        let d = drift(&times, seed);
        let rotation = data.cell.tracker.as_ref().unwrap().pose.rotation;
        for (r, v) in data.records.records.iter_mut().zip(&d) {
            r.measured += rotation.transpose() * v;
        }
        let diagnosis = run(&model_text, &data.records, &DiagnoseOptions::default());
        let Some(f) = diagnosis.report.findings.iter().find(|f| f.label == LABEL) else {
            eprintln!(
                "seed {seed}: {LABEL} not found: {}",
                diagnosis.report.summary
            );
            continue;
        };
        found += 1;
        let p = &f.parameters[PARAM];
        let truth = truth(&data.cell, &format!("{LABEL}.{PARAM}"));
        let z = (p.value - truth) / p.sigma.expect("σ");
        z_scores.push(z);
        within1 += (z.abs() <= 1.0) as usize;
        within2 += (z.abs() <= 2.0) as usize;
        let widened = diagnosis
            .report
            .uncertainty
            .widened
            .get(&format!("{LABEL}.{PARAM}"))
            .copied()
            .unwrap_or(1.0);
        classical1 += (z.abs() * widened <= 1.0) as usize;
        classical2 += (z.abs() * widened <= 2.0) as usize;
        eprintln!(
            "seed {seed}: {PARAM} {:.4e} ± {:.2e} (z {z:+.2}, independent rows z {:+.2}); {:?}",
            p.value,
            p.sigma.unwrap(),
            z * widened,
            diagnosis
                .report
                .findings
                .iter()
                .map(|f| &f.label)
                .collect::<Vec<_>>()
        );
    }
    // over all runs: a run that missed the reversal covers nothing
    let misses = n as usize - found;
    let (r1, r2, miss_rate) = (
        within1 as f64 / n.max(1) as f64,
        within2 as f64 / n.max(1) as f64,
        misses as f64 / n.max(1) as f64,
    );
    let rms_z = (z_scores.iter().map(|z| z * z).sum::<f64>() / z_scores.len().max(1) as f64).sqrt();
    eprintln!(
        "independent rows, of all runs: within 1σ {:.3}, 2σ {:.3}",
        classical1 as f64 / n.max(1) as f64,
        classical2 as f64 / n.max(1) as f64
    );
    eprintln!(
        "of {n} runs: {misses} missed {LABEL} (miss rate {miss_rate:.3}); within 1σ {r1:.3}, within 2σ {r2:.3} of all runs ({:.3}, {:.3} of the {found} that found it), RMS z {rms_z:.2} ({:.0} s)",
        within1 as f64 / found.max(1) as f64,
        within2 as f64 / found.max(1) as f64,
        started.elapsed().as_secs_f64()
    );
    // the drift hides the reversal from the selection in about a quarter of the runs (a
    // selection matter: bounded here on its own)
    assert!(
        miss_rate <= MAX_MISS_RATE,
        "{LABEL} was missed in {misses} of {n} runs (at most {MAX_MISS_RATE} allowed)"
    );
    assert!(
        r1 >= MIN_WITHIN_1,
        "the truth within 1σ in {r1:.3} of all runs ({misses} misses), expected ≥ {MIN_WITHIN_1}"
    );
    assert!(
        r2 >= MIN_WITHIN_2,
        "the truth within 2σ in {r2:.3} of all runs ({misses} misses), expected ≥ {MIN_WITHIN_2}"
    );
    assert!(
        r1 <= 0.9,
        "within 1σ in {r1:.3} of all runs: the σ are grossly over-conservative"
    );
}
