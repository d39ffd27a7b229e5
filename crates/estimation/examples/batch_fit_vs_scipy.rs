//! Benchmark: batch identification of the full XFYZ model (21 geometric errors of order 2–3,
//! the tracker's pose and warm-up) from 10 000 tracker readings, through the real records →
//! residuals path (`metrocell_estimation::fit` on a `RecordSet`), against
//! `scipy.optimize.least_squares(method="trf")` with the analytic Jacobian, on the identical
//! problem (the same whitened residuals and Jacobian, evaluated by the shared model and handed
//! to scipy over a pipe) from the identical start. Prints both wall times and their ratio on
//! the whole job (scipy's own work plus the model evaluations it asked for, against metrocell's
//! fit, which evaluates the model too), the ratios with and without the pipe, and how far apart
//! the solutions are.
//!
//! `METROCELL_PYTHON=/path/to/python cargo run --release -p metrocell-estimation --example batch_fit_vs_scipy`
//! (`-- --fit-only N` runs only metrocell's fit N more times, then times N model evaluations of
//! each kind — the first of a new problem, with J's free or all columns, r alone — for a
//! profiler; `--no-evaluations` leaves those out)

#[path = "../tests/common/mod.rs"]
mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Command, Stdio};
use std::time::Instant;

use common::{records, Planned, THESIS_TRACKER};
use metrocell_estimation::{fit, Fit, FitOptions, MeasurementRecord, PointResiduals};
use metrocell_model::ForwardModel;
use metrocell_solver::{Loss, Problem};
use metrocell_twin::CellModel;
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const READINGS: usize = 10_000;
/// Each side's solve is timed this many times and the fastest counts (the machine is shared).
const RUNS: usize = 3;

fn model() -> CellModel {
    let terms = common::xfyz_geometric_terms("[y, z]", "[0 m, 0.05 m, -0.15 m]");
    let text = format!("name: bench\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {{x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}}\n  tool_offset: [0 mm, 0 mm, -150 mm]\nsensors:\n  tracker:\n    pose: {{translation: [-0.95 m, 0.3 m, 0.62 m], euler_xyz: [0 deg, 0 deg, 56 deg]}}\n    warmup: {{offset: 0 um, amplitude: 50 um, time_constant: 60 min}}\nterms:\n{terms}");
    CellModel::from_yaml_str_in(&text, "bench.yaml", std::path::Path::new("."))
        .expect("bench model")
}

fn main() {
    let python = std::env::var("METROCELL_PYTHON").unwrap_or_else(|_| "python3".into());
    let m = model();
    let fm = m.forward_model().unwrap();
    let names = fm.param_names();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let truth = truth_of(&fm.params(), &names, &mut rng);
    let plan = readings_plan(&mut rng);
    let data = records(&fm, &truth, &plan, THESIS_TRACKER, Some(1));
    // the identical, full-rank problem for both: hold what the design cannot separate first
    let options = FitOptions {
        loss: Loss::Linear,
        ..FitOptions::default()
    };
    let t = Instant::now();
    let probe = fit(&fm, &m.setup, &data, None, &options).expect("fit");
    let probe_seconds = t.elapsed().as_secs_f64();
    let mut setup = m.setup.clone();
    for h in &probe.held {
        setup.free[h.index] = false;
    }
    let free: Vec<usize> = (0..names.len()).filter(|&k| setup.free[k]).collect();
    let x0 = metrocell_estimation::start_vector(&fm, &setup, &data).unwrap();
    println!("{} readings, {} parameters, {} free after holding {} the design cannot separate (found by a fit of all 75 in {:.3} s)", READINGS, names.len(), free.len(), probe.held.len(), probe_seconds);

    // ours: the whole fit (start checks, solve, covariance, identifiability), best of RUNS
    let mut ours = f64::INFINITY;
    let mut result = None;
    for _ in 0..RUNS {
        let t = Instant::now();
        let f = fit(&fm, &setup, &data, Some(x0.clone()), &options).expect("fit");
        ours = ours.min(t.elapsed().as_secs_f64());
        result = Some(f);
    }
    let f = result.unwrap();
    println!("metrocell: {:.3} s ({} iterations, {} evaluations, {:?}), residual RMS {:.3} µm, {} more held: {:?}", ours, f.solution.iterations, f.solution.evaluations, f.solution.termination, metrocell_estimation::rms(&f.residuals_after) * 1e6, f.held.len(), f.held.iter().map(|h| &h.combination).collect::<Vec<_>>());
    // `--fit-only N`: only metrocell's fit, N more times, for a profiler (no scipy)
    let args: Vec<String> = std::env::args().collect();
    if let Some(k) = args.iter().position(|a| a == "--fit-only") {
        let n: usize = args
            .get(k + 1)
            .and_then(|v| v.parse().ok())
            .expect("--fit-only N");
        let t = Instant::now();
        for _ in 0..n {
            fit(&fm, &setup, &data, Some(x0.clone()), &options).expect("fit");
        }
        println!(
            "{n} more fits: {:.3} s each",
            t.elapsed().as_secs_f64() / n as f64
        );
        if !args.iter().any(|a| a == "--no-evaluations") {
            let wanted: Vec<bool> = (0..names.len()).map(|k| setup.free[k]).collect();
            time_evaluations(&fm, &data.records, &x0, &wanted, n);
        }
        return;
    }
    let (what, best) = fastest_scipy(&python, &fm, &data.records, &x0, &free);
    // the like-for-like job: scipy's own work plus the model evaluations it asked for (as
    // metrocell's fit evaluates the model too), without the pipe's copying of 11 MB Jacobians
    println!("ratio scipy / metrocell: {:.1}× on the whole job (scipy at its faster setting, {what}: own work + its {} model evaluations, {:.3} s back to back = {:.3} s; pipe transfer excluded); {:.1}× on scipy's wall time including the pipe; {:.1}× on scipy's own work alone", best.job() / ours, best.evaluations, best.tight, best.job(), best.seconds / ours, (best.seconds - best.waiting) / ours);
    print_agreement(&f, &best.x, &free, &names);
}

/// The benchmark's truth: the geometric errors drawn at random (±8 µm, ±20 µrad), the tracker's
/// pose and warm-up set, the rest at the model's values `p`.
fn truth_of(p: &[f64], names: &[String], rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut truth = p.to_vec();
    for (k, n) in names.iter().enumerate() {
        if n.starts_with("positioning") || n.starts_with("straightness") {
            truth[k] = rng.random_range(-8e-6..8e-6);
        } else if n.starts_with("angular") || n.starts_with("squareness") {
            truth[k] = rng.random_range(-20e-6..20e-6);
        }
    }
    let pose = names.iter().position(|n| n == "tracker_pose.tx").unwrap();
    truth[pose..pose + 6].copy_from_slice(&[
        -0.863527,
        0.194373,
        0.677782,
        0.0339f64.to_radians(),
        0.0343f64.to_radians(),
        59.4652f64.to_radians(),
    ]);
    let w = names
        .iter()
        .position(|n| n == "tracker_warmup.offset")
        .unwrap();
    truth[w..w + 3].copy_from_slice(&[2e-6, 75e-6, 5400.0]);
    truth
}

/// READINGS random points over the travel, 1.5 s apart, each approached from a random side.
fn readings_plan(rng: &mut ChaCha8Rng) -> Vec<Planned> {
    (0..READINGS)
        .map(|k| {
            let dir = if rng.random::<bool>() { 1.0 } else { -1.0 };
            Planned {
                q: vec![
                    rng.random_range(0.0..0.8),
                    rng.random_range(0.0..0.5),
                    rng.random_range(0.0..0.4),
                ],
                approach: [dir; 3],
                temperatures: vec![],
                time_on: 600.0 + 1.5 * k as f64,
                tool_offset_shift: None,
            }
        })
        .collect()
}

/// The model evaluation alone (residuals + Jacobian of all records), as the fit calls it: the
/// first of a new problem, then with the free or all columns, then the residuals alone; `n`
/// times each.
fn time_evaluations(
    fm: &ForwardModel,
    records: &[MeasurementRecord],
    x0: &[f64],
    wanted: &[bool],
    n: usize,
) {
    let problem = PointResiduals::new(fm, records).unwrap();
    let mut r = vec![0.0; problem.residual_count()];
    let mut jac = DMatrix::zeros(problem.residual_count(), wanted.len());
    let t = Instant::now();
    for _ in 0..n {
        let problem = PointResiduals::new(fm, records).unwrap();
        problem
            .residuals_and_jacobian_of(x0, &mut r, &mut jac, wanted)
            .unwrap();
    }
    println!(
        "first residuals + Jacobian (free columns) of a new problem: {:.2} ms",
        1e3 * t.elapsed().as_secs_f64() / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        problem
            .residuals_and_jacobian_of(x0, &mut r, &mut jac, wanted)
            .unwrap();
    }
    println!(
        "residuals + Jacobian (free columns): {:.2} ms each",
        1e3 * t.elapsed().as_secs_f64() / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        problem
            .residuals_and_jacobian(x0, &mut r, &mut jac)
            .unwrap();
    }
    println!(
        "residuals + Jacobian (all columns): {:.2} ms each",
        1e3 * t.elapsed().as_secs_f64() / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        problem.residuals(x0, &mut r).unwrap();
    }
    println!(
        "residuals alone: {:.2} ms each",
        1e3 * t.elapsed().as_secs_f64() / n as f64
    );
}

/// scipy on the identical problem, with numpy's BLAS as the environment sets it and with one
/// thread (on a shared 2-core machine OpenBLAS's second thread has made scipy's own work 2–3×
/// slower, not faster), each printed: the faster of the two is the peer.
fn fastest_scipy(
    python: &str,
    fm: &ForwardModel,
    records: &[MeasurementRecord],
    x0: &[f64],
    free: &[usize],
) -> (&'static str, ScipySession) {
    let problem = PointResiduals::new(fm, records).unwrap();
    let specs: Vec<_> = fm
        .machine_terms
        .param_specs()
        .into_iter()
        .chain(fm.instrument_terms.param_specs())
        .collect();
    let session =
        |threads: Option<&str>| scipy_session(python, threads, &problem, x0, free, &specs);
    let one_thread_already = std::env::var("OPENBLAS_NUM_THREADS").is_ok_and(|v| v == "1");
    let mut sessions = vec![("BLAS threads as set", session(None))];
    if !one_thread_already {
        sessions.push(("one BLAS thread", session(Some("1"))));
    }
    for (what, s) in &sessions {
        println!("scipy trf, {what} (fastest own work of {RUNS}): {:.3} s ({} evaluations, status {}), of which {:.3} s waiting for metrocell's residuals and Jacobian over the pipe ({:.3} s evaluating them); + its evaluations back to back {:.3} s = whole job {:.3} s", s.seconds, s.evaluations, s.status, s.waiting, s.evaluating, s.tight, s.job());
    }
    sessions
        .into_iter()
        .min_by(|a, b| a.1.job().total_cmp(&b.1.job()))
        .unwrap()
}

/// How far apart the solutions are: per parameter relative to its own magnitude (floored at its
/// σ) and in σ, and in the ∞-norm.
fn print_agreement(f: &Fit, xs: &[f64], free: &[usize], names: &[String]) {
    let mut worst_rel: f64 = 0.0;
    let mut worst_sigma: f64 = 0.0;
    let mut worst_name = String::new();
    for (i, &k) in free.iter().enumerate() {
        let d = (f.x[k] - xs[i]).abs();
        let sigma = f.parameters[k].sigma.unwrap_or(f64::INFINITY);
        let rel = d / f.x[k].abs().max(sigma);
        if rel > worst_rel {
            worst_rel = rel;
            worst_name = names[k].clone();
        }
        worst_sigma = worst_sigma.max(d / sigma);
    }
    let inf_rel = free
        .iter()
        .enumerate()
        .map(|(i, &k)| (f.x[k] - xs[i]).abs())
        .fold(0.0, f64::max)
        / free.iter().map(|&k| f.x[k].abs()).fold(0.0, f64::max);
    println!("solutions: ‖Δx‖∞/‖x‖∞ = {inf_rel:.2e}; worst parameter {worst_name}: {worst_rel:.2e} of max(|x|, σ); largest difference {worst_sigma:.2e} σ");
}

/// One scipy process's solves of the problem and what they cost.
struct ScipySession {
    /// The fastest run's wall time, of which `waiting` for metrocell's evaluations over the pipe.
    seconds: f64,
    waiting: f64,
    /// metrocell's time evaluating per run, as served over the pipe.
    evaluating: f64,
    evaluations: usize,
    status: serde_json::Value,
    /// The evaluations scipy asked for, timed back to back (fastest of 3 passes).
    tight: f64,
    x: Vec<f64>,
}

impl ScipySession {
    /// scipy's own work plus the model evaluations it asked for.
    fn job(&self) -> f64 {
        self.seconds - self.waiting + self.tight
    }
}

/// `scipy_batch_fit.py` on the free parameters of `problem` from `x0`, RUNS times, with
/// `OPENBLAS_NUM_THREADS` (and OpenMP's) set to `threads` when given.
fn scipy_session(
    python: &str,
    threads: Option<&str>,
    problem: &PointResiduals,
    x0: &[f64],
    free: &[usize],
    specs: &[metrocell_physics::ParamSpec],
) -> ScipySession {
    let rows = problem.residual_count();
    // the possible range (JSON has no infinity: an unbounded side goes as null)
    let lower: Vec<Option<f64>> = free
        .iter()
        .map(|&k| Some(specs[k].possible.lo.min(x0[k])).filter(|v| v.is_finite()))
        .collect();
    let upper: Vec<Option<f64>> = free
        .iter()
        .map(|&k| Some(specs[k].possible.hi.max(x0[k])).filter(|v| v.is_finite()))
        .collect();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/scipy_batch_fit.py");
    let mut command = Command::new(python);
    if let Some(t) = threads {
        command
            .env("OPENBLAS_NUM_THREADS", t)
            .env("OMP_NUM_THREADS", t);
    }
    let mut child = command
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| {
            panic!("cannot start {python}: {e} (set METROCELL_PYTHON to a python with scipy)")
        });
    let mut to = child.stdin.take().unwrap();
    let mut from = BufReader::new(child.stdout.take().unwrap());
    let head = serde_json::json!({"n": free.len(), "m": rows, "x0": free.iter().map(|&k| x0[k]).collect::<Vec<_>>(), "lower": lower, "upper": upper, "runs": RUNS});
    writeln!(to, "{head}").unwrap();
    to.flush().unwrap();
    let n = problem.parameter_count();
    let mut r = vec![0.0; rows];
    let mut jac = DMatrix::zeros(rows, n);
    let mut x = x0.to_vec();
    let wanted: Vec<bool> = (0..n).map(|k| free.contains(&k)).collect();
    let mut ours_eval = 0.0;
    let done = loop {
        let mut tag = [0u8; 1];
        from.read_exact(&mut tag).unwrap();
        if tag[0] == b'D' {
            let mut line = String::new();
            from.read_line(&mut line).unwrap();
            break serde_json::from_str::<serde_json::Value>(&line).unwrap();
        }
        let mut buf = vec![0u8; 8 * free.len()];
        from.read_exact(&mut buf).unwrap();
        for (i, &k) in free.iter().enumerate() {
            x[k] = f64::from_le_bytes(buf[8 * i..8 * i + 8].try_into().unwrap());
        }
        let te = Instant::now();
        // the free columns only, as metrocell's fit asks for them (scipy is sent only those)
        problem
            .residuals_and_jacobian_of(&x, &mut r, &mut jac, &wanted)
            .unwrap();
        ours_eval += te.elapsed().as_secs_f64();
        let mut bytes = Vec::with_capacity(8 * rows * (1 + free.len()));
        r.iter()
            .for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
        for i in 0..rows {
            for &k in free {
                bytes.extend_from_slice(&jac[(i, k)].to_le_bytes());
            }
        }
        to.write_all(&bytes).unwrap();
        to.flush().unwrap();
    };
    child.wait().unwrap();
    // scipy's fastest run, and metrocell's evaluation time per run (the runs ask for the same points)
    let seconds = |key: &str| -> Vec<f64> {
        done[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (runs, waits) = (seconds("seconds"), seconds("evaluation_seconds"));
    let best = (0..RUNS)
        .min_by(|&a, &b| (runs[a] - waits[a]).total_cmp(&(runs[b] - waits[b])))
        .unwrap();
    // the evaluations charged to scipy are timed back to back, as the fit makes them: between
    // the pipe's 11 MB copies the same evaluation runs slower (caches cold), which would
    // flatter metrocell; the fastest of 3 passes of as many evaluations as scipy made
    let evaluations = done["evaluations"].as_u64().unwrap() as usize;
    let tight = (0..3)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..evaluations {
                problem
                    .residuals_and_jacobian_of(x0, &mut r, &mut jac, &wanted)
                    .unwrap();
            }
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min);
    ScipySession {
        seconds: runs[best],
        waiting: waits[best],
        evaluating: ours_eval / RUNS as f64,
        evaluations,
        status: done["status"].clone(),
        tight,
        x: done["x"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect(),
    }
}
