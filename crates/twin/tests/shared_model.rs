//! The twin is a user of the shared forward model (crates/model):
//! * identity — for every example cell (every family; the delta printer, which has no tracker,
//!   gets one added) the twin's noise-free tracker readings equal the model's predictions at the
//!   true parameters bit for bit, with the signals the twin used (`Simulation::signals_at`, the
//!   sample's station air, the tracker's time since power-on);
//! * statistics — the noisy readings' residuals against the model, divided by the stated σ,
//!   have mean 0 ± 3/√n and standard deviation 1 ± 0.05;
//! * Jacobians — the model's analytic Jacobian of the reading w.r.t. every parameter (kinematic
//!   terms of the delta and the arm included) matches 4th-order central differences to 1e-6
//!   relative.

mod common;

use metrocell_physics::Signals;
use metrocell_twin::cell_file::CellFile;
use metrocell_twin::{Cell, Sample, SampleTruth, Simulation, TrackerSample, TrackerTruth};
use nalgebra::DMatrix;

const CELLS: [&str; 5] = ["quick_demo.yaml", "xfyz_shift.yaml", "five_axis_table.yaml", "serial_arm_ur5.yaml", "delta_printer.yaml"];

/// A tracker for the delta printer, which has none: on the bed's side, looking at the effector.
const DELTA_TRACKER: &str = "
pose: {translation: [1.1 m, -0.4 m, 0.3 m], euler_xyz: [0 deg, 0 deg, 160 deg]}
rate: 10 Hz
range_noise: {constant: 4 um, per_metre: 0.8 um/m}
angular_noise: 3 urad
warmup: {offset: 2 um, amplitude: 19 um, time_constant: 30 min}
station: {temperature_bias: 0.3 K, pressure_bias: 40 Pa, humidity_bias: 5}
";

fn example_with_tracker(name: &str) -> CellFile {
    let mut f = common::example_file(name);
    if f.sensors.tracker.is_none() {
        f.sensors.tracker = Some(serde_yaml::from_str(DELTA_TRACKER).unwrap());
    }
    f
}

/// The example with every noise source of the tracker and its station removed (biases kept).
fn noise_free(name: &str) -> Cell {
    let mut f = example_with_tracker(name);
    let t = f.sensors.tracker.as_mut().unwrap();
    t.turbulence.clear();
    t.beam_breaks = None;
    let mut cell = common::validate(&f);
    let tr = cell.tracker.as_mut().unwrap();
    tr.range_noise_constant = 0.0;
    tr.range_noise_per_metre = 0.0;
    tr.angular_noise = 0.0;
    tr.station.temperature_noise = 0.0;
    tr.station.pressure_noise = 0.0;
    tr.station.humidity_noise = 0.0;
    cell
}

fn tracker_readings(sim: &Simulation) -> Vec<(TrackerSample, TrackerTruth)> {
    sim.samples_with_truth()
        .filter_map(|(s, t)| match (s, t) {
            (Sample::Tracker(s), SampleTruth::Tracker(t)) if s.range.is_finite() => Some((s, t)),
            _ => None,
        })
        .collect()
}

/// The signals of a tracker reading as a recording gives them.
fn reading_signals(sim: &Simulation, s: &TrackerSample) -> Signals {
    let mut sig = sim.signals_at(s.t);
    sig.air_temperature = Some(s.air_temperature);
    sig.air_pressure = Some(s.air_pressure);
    sig.air_humidity = Some(s.air_humidity);
    sig.time_since_power_on = Some(s.t + sim.cell().tracker.as_ref().unwrap().powered_on_before_start);
    sig
}

#[test]
fn noise_free_readings_are_the_models_predictions_bit_for_bit() {
    for name in CELLS {
        let sim = Simulation::new(noise_free(name), 20.0, 11).unwrap();
        let model = sim.forward_model();
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        let readings = tracker_readings(&sim);
        assert!(readings.len() >= 150, "{name}: {} readings", readings.len());
        for (s, tt) in &readings {
            let mut sig = reading_signals(&sim, s);
            let tool = model.tool_state(&p, &kin, &tt.joints, &mut sig, None).unwrap();
            assert_eq!(tool.truth.translation.vector, tt.tool_point, "{name} t = {}: tool point", s.t);
            let pred = model.tracker(&p, tool.truth.translation.vector, &mut sig).unwrap();
            assert_eq!(pred.measured_range().to_bits(), s.range.to_bits(), "{name} t = {}: range {} vs {}", s.t, pred.measured_range(), s.range);
            assert_eq!(pred.measured_point(), s.point, "{name} t = {}: point", s.t);
            assert_eq!((pred.azimuth, pred.elevation), (s.azimuth, s.elevation), "{name} t = {}", s.t);
        }
        // the warm-up is really in the readings (every tracker here has one)
        let (s, tt) = &readings[readings.len() / 2];
        let pred = model.tracker(&p, tt.tool_point, &mut reading_signals(&sim, s)).unwrap();
        assert!(pred.warmup > 0.0 && tt.warmup_range_error == pred.warmup, "{name}: warm-up {} m", pred.warmup);
    }
}

#[test]
fn noisy_residuals_over_the_stated_sigma_are_standard_normal() {
    for (seed, name) in ["quick_demo.yaml", "xfyz_shift.yaml", "serial_arm_ur5.yaml"].into_iter().enumerate() {
        let mut f = example_with_tracker(name);
        let t = f.sensors.tracker.as_mut().unwrap();
        // turbulence inflates the scatter above the stated σ on purpose; breaks give no reading
        t.turbulence.clear();
        t.beam_breaks = None;
        let sim = Simulation::new(common::validate(&f), 300.0, 5 + seed as u64).unwrap();
        let spec = sim.cell().tracker.clone().unwrap();
        let model = sim.forward_model();
        let p = model.params();
        let mut z = Vec::new();
        for (s, tt) in tracker_readings(&sim) {
            // the estimator's view: the recorded station air and the true tool point
            let mut sig = Signals { air_temperature: Some(s.air_temperature), air_pressure: Some(s.air_pressure), air_humidity: Some(s.air_humidity), time_since_power_on: Some(s.t + spec.powered_on_before_start), ..Default::default() };
            let pred = model.tracker(&p, tt.tool_point, &mut sig).unwrap();
            let stated_range = spec.range_noise_constant + spec.range_noise_per_metre * s.range;
            z.push((s.range - pred.measured_range()) / stated_range);
            z.push((s.azimuth - pred.azimuth) / spec.angular_noise);
            z.push((s.elevation - pred.elevation) / spec.angular_noise);
        }
        let (mean, std) = common::mean_std(&z);
        let n = z.len() as f64;
        println!("{name}: n = {n}, mean {mean:.4}, std {std:.4}");
        assert!(n >= 8000.0, "{name}: n = {n}");
        assert!(mean.abs() < 3.0 / n.sqrt(), "{name}: mean {mean}");
        assert!((std - 1.0).abs() < 0.05, "{name}: std {std}");
    }
}

/// Reported point (3) and measured range of the model at parameters `p`.
fn reading(sim: &Simulation, p: &[f64], joints: &[f64], sig: &Signals) -> [f64; 4] {
    let model = sim.forward_model();
    let kin = model.kinematic_truth(p).unwrap();
    let mut s = sig.clone();
    let tool = model.tool_state(p, &kin, joints, &mut s, None).unwrap();
    let pred = model.tracker(p, tool.truth.translation.vector, &mut s).unwrap();
    let y = pred.measured_point();
    [y.x, y.y, y.z, pred.measured_range()]
}

/// The example cells, plus the UR5 with a tool offset (a tool-frame term the joint offsets turn)
/// and a two-link URDF arm (link lengths along the URDF origins).
fn jacobian_cells() -> Vec<(String, Cell)> {
    let mut cells: Vec<(String, Cell)> = CELLS.iter().map(|n| (n.to_string(), common::validate(&example_with_tracker(n)))).collect();
    let text = common::edited_example("serial_arm_ur5.yaml", "  - id: thermal_growth\n", "  - {id: tool_offset, params: {dx: 0.2 mm, dy: -0.1 mm, dz: 0.3 mm}}\n  - id: thermal_growth\n");
    cells.push(("ur5 + tool_offset".into(), Cell::from_yaml_str(&text, "ur5_tool_offset.yaml").unwrap()));
    let dir = std::env::temp_dir().join(format!("metrocell-twin-shared-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("two_link.urdf"), common::TWO_LINK_URDF).unwrap();
    let text = std::fs::read_to_string(common::cell_path("serial_arm_ur5.yaml")).unwrap();
    let (m0, m1) = (text.find("  serial_arm:\n").unwrap(), text.find("\nsensors:").unwrap());
    let (p0, p1) = (text.find("  joints:\n").unwrap(), text.find("  feed_rate:").unwrap());
    let t0 = text.find("\nterms:").unwrap();
    let arm = "  serial_arm:\n    urdf: {path: two_link.urdf, root_link: base, tip_link: tip}\n";
    let program = "  joints:\n    - [10 deg, 20 deg]\n    - [30 deg, 60 deg]\n";
    let terms = "\nterms:\n  - {id: joint_offset, options: {joints: 2}, params: {q1: 0.1 mrad, q2: 0.5 mrad}}\n  - {id: link_length, options: {links: 3}, params: {l1: 0.1 mm, l2: -0.2 mm, l3: 0.2 mm}}\n  - {id: tool_offset, params: {dx: 0.2 mm, dy: -0.1 mm, dz: 0.3 mm}}\n";
    std::fs::write(dir.join("cell.yaml"), format!("{}{}{}{}{}{}", &text[..m0], arm, &text[m1..p0], program, &text[p1..t0], terms)).unwrap();
    cells.push(("two-link URDF arm".into(), Cell::from_path(dir.join("cell.yaml")).unwrap_or_else(|e| panic!("{e}"))));
    std::fs::remove_dir_all(&dir).unwrap();
    cells
}

#[test]
fn analytic_jacobians_match_central_differences() {
    for (name, cell) in jacobian_cells() {
        let sim = Simulation::new(cell, 12.0, 3).unwrap();
        let model = sim.forward_model();
        let names = model.param_names();
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        let readings = tracker_readings(&sim);
        let mut checked = 0;
        for (s, tt) in readings.iter().step_by(37) {
            let sig = reading_signals(&sim, s);
            let mut j = DMatrix::zeros(metrocell_model::TRACKER_ROWS, model.param_count());
            let mut work = metrocell_model::Workspace::new(&model);
            let pred = model.tracker_jacobian(&p, &kin, &tt.joints, &mut sig.clone(), &mut work, &mut j).unwrap();
            let y = reading(&sim, &p, &tt.joints, &sig);
            assert_eq!(y[3], pred.measured_range(), "{name}: the Jacobian's prediction is the model's");
            // a column below 1e-9 of the largest entry is zero up to rounding (e.g. the arm's
            // last joint turning the tool point about itself)
            let floor = 1e-9 * j.amax();
            for c in 0..p.len() {
                let col = j.column(c);
                let scale = col.amax().max(floor);
                // a step that moves the reading by ~1 µm, and at most 0.1 % of the parameter
                let mut h = if scale > 0.0 { 1e-6 / scale } else { 1e-6 };
                if p[c] != 0.0 {
                    h = h.min(1e-3 * p[c].abs());
                }
                let at = |k: f64| {
                    let mut q = p.clone();
                    q[c] += k * h;
                    reading(&sim, &q, &tt.joints, &sig)
                };
                let (m2, m1, p1, p2) = (at(-2.0), at(-1.0), at(1.0), at(2.0));
                for r in 0..4 {
                    let fd = (m2[r] - 8.0 * m1[r] + 8.0 * p1[r] - p2[r]) / (12.0 * h);
                    let err = (fd - col[r]).abs();
                    // plus the rounding error of the stencil itself (≈ 18·ε·|y|/(12·h))
                    let rounding = 4.0 * f64::EPSILON * y[3].abs() / h;
                    assert!(err <= 1e-6 * scale + rounding, "{name} t = {}: ∂y{r}/∂{} analytic {} vs central {fd} (column scale {scale})", s.t, names[c], col[r]);
                }
            }
            checked += 1;
        }
        assert!(checked >= 3, "{name}: {checked} readings checked");
        // every term of the cell has a parameter in the Jacobian
        assert!(names.iter().any(|n| n.starts_with("tracker_pose.")) && names.iter().any(|n| n.starts_with("refraction.")), "{name}: {names:?}");
        let kinematic = ["delta_", "joint_offset.", "link_length."];
        if name.contains("delta") || name.contains("arm") || name.contains("ur5") {
            assert!(names.iter().any(|n| kinematic.iter().any(|k| n.starts_with(k))), "{name}: no kinematic term in {names:?}");
        }
    }
}

/// The `estimation` section: free parameters and priors per term label, checked against the
/// terms with errors naming the key.
#[test]
fn estimation_section_gives_the_free_mask_and_priors() {
    let add = "\nestimation:\n  \"positioning[y]\": {free: [c1, c2], priors: {c0: {value: 0 um, sigma: 5 um}}}\n  tracker_pose: {free: [tx, ty, tz]}\n";
    let text = std::fs::read_to_string(common::cell_path("xfyz_shift.yaml")).unwrap() + add;
    let cell = Cell::from_yaml_str(&text, "estimation.yaml").unwrap();
    let setup = cell.parameter_setup().unwrap();
    let at = |n: &str| setup.names.iter().position(|x| x == n).unwrap_or_else(|| panic!("{n} not in {:?}", setup.names));
    assert!(!setup.free[at("positioning[y].c0")] && setup.free[at("positioning[y].c1")] && setup.free[at("positioning[y].c2")]);
    assert!(setup.free[at("tracker_pose.tz")] && !setup.free[at("tracker_pose.alpha")]);
    assert!(setup.free[at("squareness[xy].s")], "terms without settings stay free");
    assert_eq!(setup.priors[at("positioning[y].c0")], Some(metrocell_model::Prior { value: 0.0, sigma: 5e-6 }));
    assert_eq!(setup.priors.iter().filter(|p| p.is_some()).count(), 1);
    // fixed: positioning[y].c0 and tracker_pose's three angles
    assert_eq!(setup.free.iter().filter(|f| !**f).count(), 4);

    for (bad, needles) in [
        ("\nestimation:\n  \"positioning[q]\": {free: [c0]}\n", vec!["estimation.positioning[q]", "positioning[y]", "tracker_pose"]),
        ("\nestimation:\n  \"positioning[y]\": {free: [c7]}\n", vec!["estimation.positioning[y].free", "c7", "allowed: c0, c1, c2"]),
        ("\nestimation:\n  \"positioning[y]\": {priors: {c0: {value: 0 um, sigma: 0 um}}}\n", vec!["estimation.positioning[y].priors.c0", "σ > 0"]),
        ("\nestimation:\n  tracker_pose: {priors: {tx: {value: 3 K, sigma: 1 mm}}}\n", vec!["estimation.tracker_pose.priors.tx.value", "`K`"]),
    ] {
        let text = std::fs::read_to_string(common::cell_path("xfyz_shift.yaml")).unwrap() + bad;
        let msg = common::error_of(&text);
        common::assert_mentions(&msg, &needles);
    }
}

/// The declared parallel pairs really are parallel: their Jacobian columns are equal up to the
/// declared sign at every reading (and the cells declare the ones expected).
#[test]
fn declared_parallel_pairs_have_parallel_jacobian_columns() {
    let text = common::edited_example("xfyz_shift.yaml", "  - id: squareness\n", "  - {id: tool_offset, params: {dx: 0.1 mm, dy: 0 mm, dz: -0.2 mm}}\n  - id: squareness\n");
    let cells = [("xfyz + tool_offset", Cell::from_yaml_str(&text, "xfyz_tool.yaml").unwrap(), 5), ("xfyz_shift", common::validate(&common::example_file("xfyz_shift.yaml")), 1), ("five_axis_table", common::validate(&common::example_file("five_axis_table.yaml")), 0)];
    for (name, cell, expected) in cells {
        let sim = Simulation::new(cell, 6.0, 2).unwrap();
        let model = sim.forward_model();
        let names = model.param_names();
        let pairs = model.parallel_pairs();
        assert_eq!(pairs.len(), expected, "{name}: {:?}", pairs.iter().map(|p| (&names[p.a], &names[p.b])).collect::<Vec<_>>());
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        let mut work = metrocell_model::Workspace::new(&model);
        let mut j = DMatrix::zeros(metrocell_model::TRACKER_ROWS, model.param_count());
        for (s, tt) in tracker_readings(&sim).iter().step_by(13) {
            model.tracker_jacobian(&p, &kin, &tt.joints, &mut reading_signals(&sim, s), &mut work, &mut j).unwrap();
            for pair in &pairs {
                let (a, b) = (j.column(pair.a), j.column(pair.b));
                assert!((a - b * pair.sign).amax() <= 1e-9 * a.amax(), "{name}: {} vs {}: {a} vs {b}", names[pair.a], names[pair.b]);
                assert!(a.amax() > 0.1, "{name}: {} moves the reading", names[pair.a]);
            }
        }
    }
}
