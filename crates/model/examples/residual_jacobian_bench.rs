//! Residual + analytic Jacobian of the full XFYZ tracker model for 10 000 readings.
//!
//! Model: the 21 geometric errors of an XFYZ machine (3 positioning and 6 straightness errors of
//! order 3, 9 angular errors of order 2 with their Abbe levers, 3 squareness), the tracker pose,
//! warm-up and refraction: 66 + 11 = 77 parameters. For each reading: the predicted tracker
//! reading (point, range) through the shared forward model, the residual against a synthetic
//! measurement, and the 4 × 77 Jacobian into a caller-provided buffer.
//!
//! Baseline measured in the same run: `TermModel::displacement` (the per-call-allocating sum of
//! the terms' displacements and Jacobians, as on main) for the 21 machine terms alone — it
//! does less work than the new path (no tracker chain), so the ratio is a lower bound.
//!
//! Allocations are counted (a counting global allocator): the new path must make none per
//! reading; the count of each path is printed, and a non-zero count for the new path fails.
//!
//! `cargo run --release -p metrocell-model --example residual_jacobian_bench`

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use metrocell_model::{ForwardModel, MachineGeometry, MachineKinematics, Workspace, TRACKER_ROWS};
use metrocell_physics::model::TermModel;
use metrocell_physics::{Frame, Signals, TermConfig};
use nalgebra::{DMatrix, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const READINGS: usize = 10_000;

/// The system allocator, counting every allocation.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

/// Allocations made while `f` runs.
fn allocations_of<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let out = f();
    (out, ALLOCATIONS.load(Ordering::Relaxed) - before)
}

fn machine_terms() -> Vec<TermConfig> {
    let mut yaml = String::new();
    let travel = "travel: [0 m, 1 m]";
    for a in ["x", "y", "z"] {
        yaml += &format!("- {{id: positioning, options: {{axis: {a}, order: 3, {travel}}}, params: {{c0: 1 um, c1: 4 um, c2: -2 um, c3: 1 um}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| **d != a) {
            yaml += &format!("- {{id: straightness, options: {{axis: {a}, direction: {d}, order: 3, {travel}}}, params: {{c0: 0 um, c1: 2 um, c2: 3 um, c3: -1 um}}}}\n");
        }
        for about in ["x", "y", "z"] {
            yaml += &format!("- {{id: angular, options: {{axis: {a}, about: {about}, lever_axes: [z], abbe_offset: [0 m, 0 m, -0.15 m], order: 2, {travel}}}, params: {{c0: 5 urad, c1: 10 urad, c2: -4 urad}}}}\n");
        }
    }
    for pair in ["xy", "xz", "yz"] {
        yaml +=
            &format!("- {{id: squareness, options: {{pair: {pair}}}, params: {{s: 20 urad}}}}\n");
    }
    serde_yaml::from_str(&yaml).expect("bench terms parse")
}

fn tracker_terms() -> Vec<TermConfig> {
    serde_yaml::from_str(
        "- {id: tracker_pose, params: {tx: -0.86 m, ty: 0.19 m, tz: 0.68 m, alpha: 0.6 mrad, beta: 0.6 mrad, delta: 1.04 rad}}
- {id: tracker_warmup, params: {offset: 1 um, amplitude: 75 um, time_constant: 5400 s}}
- {id: refraction, params: {path_temperature_offset: -0.3 K, path_pressure_offset: 0 Pa}}",
    )
    .expect("bench tracker terms parse")
}

fn main() {
    let machine = MachineGeometry {
        kinematics: MachineKinematics::Cartesian("XFYZ".parse().expect("XFYZ")),
        travel: [[0.0, 1.0]; 3],
        tool_offset: Vector3::new(0.0, 0.0, -0.1),
    };
    let terms = TermModel::from_configs(&machine_terms()).expect("machine terms");
    let instruments = TermModel::from_configs(&tracker_terms()).expect("tracker terms");
    let model = ForwardModel::new(&machine, &terms, &instruments).expect("forward model");
    let p = model.params();
    let kin = model.kinematic_truth(&p).expect("kinematics");
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let readings: Vec<(Vec<f64>, Signals)> = (0..READINGS)
        .map(|k| {
            let q: Vec<f64> = (0..3).map(|_| rng.random::<f64>()).collect();
            let sign = |r: &mut ChaCha8Rng| if r.random::<bool>() { 1.0 } else { -1.0 };
            let mut s = Signals {
                air_temperature: Some(20.3),
                air_pressure: Some(101_300.0),
                air_humidity: Some(45.0),
                time_since_power_on: Some(600.0 + k as f64),
                ..Default::default()
            };
            let approach = [sign(&mut rng), sign(&mut rng), sign(&mut rng)];
            model.set_motion(&mut s, &q, &[0.0; 3], &approach);
            (q, s)
        })
        .collect();
    // synthetic measurements: the model's own readings plus 5 µm
    let measured: Vec<[f64; 4]> = readings
        .iter()
        .map(|(q, s)| {
            let mut s = s.clone();
            let tool = model
                .tool_state(&p, &kin, q, &mut s, None)
                .expect("tool state");
            let y = model.tracker(&p, &tool, &mut s).expect("tracker");
            let m = y.measured_point();
            [m.x + 5e-6, m.y - 5e-6, m.z, y.measured_range()]
        })
        .collect();
    let mut jac = DMatrix::zeros(TRACKER_ROWS, model.param_count());
    let mut ws = Workspace::new(&model);
    let mut work: Vec<Signals> = readings.iter().map(|(_, s)| s.clone()).collect();

    let mut run_new = |work: &mut [Signals], jac: &mut DMatrix<f64>| {
        let start = Instant::now();
        let mut check = 0.0;
        for (((q, _), s), m) in readings.iter().zip(work.iter_mut()).zip(&measured) {
            let y = model
                .tracker_jacobian(&p, &kin, q, s, &mut ws, jac)
                .expect("tracker Jacobian");
            let yp = y.measured_point();
            let r = [
                m[0] - yp.x,
                m[1] - yp.y,
                m[2] - yp.z,
                m[3] - y.measured_range(),
            ];
            check += r.iter().map(|v| v * v).sum::<f64>() + jac[(0, 0)];
        }
        (start.elapsed().as_secs_f64(), check)
    };
    let p_machine = &p[..terms.params().len()];
    let mut run_old = || {
        let start = Instant::now();
        let mut check = 0.0;
        for (_, s) in &readings {
            let (d, j) = terms
                .displacement(Frame::Machine, p_machine, s)
                .expect("displacement");
            check += d.norm() + j[(0, 0)];
        }
        (start.elapsed().as_secs_f64(), check)
    };
    // warm up once (counting allocations), then take the best of three
    let (_, alloc_new) = allocations_of(|| run_new(&mut work, &mut jac));
    let (_, alloc_old) = allocations_of(run_old);
    let best = |f: &mut dyn FnMut() -> (f64, f64)| {
        (0..3)
            .map(|_| f())
            .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a })
    };
    let (t_new, c_new) = best(&mut || run_new(&mut work, &mut jac));
    let (t_old, c_old) = best(&mut run_old);
    println!(
        "model: {} parameters ({} machine, {} tracker), {READINGS} tracker readings",
        model.param_count(),
        p_machine.len(),
        model.param_count() - p_machine.len()
    );
    println!("new   residual + 4×{} Jacobian (shared forward model): {:8.2} ms  ({:.2} µs/reading)  [checksum {c_new:.6e}]", model.param_count(), t_new * 1e3, t_new / READINGS as f64 * 1e6);
    println!("old   TermModel::displacement + 3×{} Jacobian (machine terms only): {:8.2} ms  ({:.2} µs/reading)  [checksum {c_old:.6e}]", p_machine.len(), t_old * 1e3, t_old / READINGS as f64 * 1e6);
    println!("ratio old/new: {:.2}×", t_old / t_new);
    println!(
        "allocations: new {alloc_new} ({:.2} per reading), old {alloc_old} ({:.2} per reading)",
        alloc_new as f64 / READINGS as f64,
        alloc_old as f64 / READINGS as f64
    );
    assert_eq!(
        alloc_new, 0,
        "the shared model's XFYZ tracker path must not allocate per reading"
    );
}
