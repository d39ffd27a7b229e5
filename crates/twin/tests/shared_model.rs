//! The twin is a user of the shared forward model (crates/model), for every instrument:
//! * identity — for every example cell (every family; the delta printer, which has no tracker,
//!   gets one added) the twin's noise-free tracker readings, probe hits and camera readings
//!   (frame poses, the plate's corner pixels and marker points) equal the model's predictions at
//!   the true parameters bit for bit, with the signals the twin used (`Simulation::signals_at`,
//!   the sample's station air, the tracker's time since power-on);
//! * statistics — for every example cell (all families), the noisy tracker readings' residuals, and
//!   the probe's, against the model, divided by the stated σ, have mean 0 ± 3/√n and standard
//!   deviation 1 ± 0.05 (the twin's camera readings carry no noise: it is added where frames are
//!   rendered, crates/sim);
//! * Jacobians — the model's analytic Jacobian of every instrument's reading w.r.t. every
//!   parameter (kinematic terms of the delta and the arm, workpiece-frame terms, time offset,
//!   compliance, probe pretravel, camera scale and lens distortion included) matches 4th-order
//!   central differences to 1e-6 relative.

mod common;

use metrocell_model::{
    ForwardModel, ProbeTarget, ToolState, Workspace, CAMERA_ROWS, PROBE_ROWS, TRACKER_ROWS,
};
use metrocell_physics::Signals;
use metrocell_twin::cell_file::CellFile;
use metrocell_twin::{
    CameraFrameRequest, Cell, ProbeHitSample, Sample, SampleTruth, Simulation, TrackerSample,
    TrackerTruth,
};
use nalgebra::{DMatrix, Isometry3, Vector3};

const CELLS: [&str; 5] = [
    "quick_demo.yaml",
    "xfyz_shift.yaml",
    "five_axis_table.yaml",
    "serial_arm_ur5.yaml",
    "delta_printer.yaml",
];

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
    noise_free_file(example_with_tracker(name))
}

/// The quick demo with the part misaligned and expanding (workpiece-frame terms).
fn demo_with_workpiece_terms() -> CellFile {
    let text = common::edited_example(
        "quick_demo.yaml",
        "  - id: thermal_scale\n",
        &format!("{WORKPIECE_TERMS}  - id: thermal_scale\n"),
    );
    serde_yaml::from_str(&text).unwrap()
}

fn noise_free_file(mut f: CellFile) -> Cell {
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
    sig.time_since_power_on =
        Some(s.t + sim.cell().tracker.as_ref().unwrap().powered_on_before_start);
    sig
}

#[test]
fn noise_free_readings_are_the_models_predictions_bit_for_bit() {
    let cells = CELLS
        .iter()
        .map(|n| (n.to_string(), noise_free(n)))
        .chain(std::iter::once((
            "quick_demo + workpiece terms".to_string(),
            noise_free_file(demo_with_workpiece_terms()),
        )));
    for (name, cell) in cells {
        let sim = Simulation::new(cell, 20.0, 11).unwrap();
        let model = sim.forward_model();
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        let readings = tracker_readings(&sim);
        assert!(readings.len() >= 150, "{name}: {} readings", readings.len());
        let mut part_moved = 0.0f64;
        for (s, tt) in &readings {
            let mut sig = reading_signals(&sim, s);
            let tool = model
                .tool_state(&p, &kin, &tt.joints, &mut sig, None)
                .unwrap();
            assert_eq!(
                tool.target(),
                tt.tool_point,
                "{name} t = {}: tool point",
                s.t
            );
            part_moved = part_moved.max(tool.workpiece.norm());
            let pred = model.tracker(&p, &tool, &mut sig).unwrap();
            assert_eq!(
                pred.measured_range().to_bits(),
                s.range.to_bits(),
                "{name} t = {}: range {} vs {}",
                s.t,
                pred.measured_range(),
                s.range
            );
            assert_eq!(pred.measured_point(), s.point, "{name} t = {}: point", s.t);
            assert_eq!(
                (pred.azimuth, pred.elevation),
                (s.azimuth, s.elevation),
                "{name} t = {}",
                s.t
            );
        }
        // the workpiece terms really move the sighted point (by tens of µm over the table)
        assert_eq!(
            name.contains("workpiece"),
            part_moved > 5e-6,
            "{name}: d_w up to {part_moved:e} m"
        );
        // the warm-up is really in the readings (every tracker here has one)
        let (s, tt) = &readings[readings.len() / 2];
        let pred = model
            .tracker(&p, &sighting(tt.tool_point), &mut reading_signals(&sim, s))
            .unwrap();
        assert!(
            pred.warmup > 0.0 && tt.warmup_range_error == pred.warmup,
            "{name}: warm-up {} m",
            pred.warmup
        );
    }
}

#[test]
fn noisy_residuals_over_the_stated_sigma_are_standard_normal() {
    for (seed, name) in CELLS.into_iter().enumerate() {
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
            let mut sig = Signals {
                air_temperature: Some(s.air_temperature),
                air_pressure: Some(s.air_pressure),
                air_humidity: Some(s.air_humidity),
                time_since_power_on: Some(s.t + spec.powered_on_before_start),
                ..Default::default()
            };
            let pred = model
                .tracker(&p, &sighting(tt.tool_point), &mut sig)
                .unwrap();
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

/// A tool state whose sighted point is `point` (what a tracker reading needs of it).
fn sighting(point: Vector3<f64>) -> ToolState {
    ToolState {
        nominal: Isometry3::identity(),
        truth: Isometry3::translation(point.x, point.y, point.z),
        d: Vector3::zeros(),
        workpiece: Vector3::zeros(),
    }
}

/// Reported point (3) and measured range of the model at parameters `p`.
fn reading(model: &ForwardModel, p: &[f64], joints: &[f64], sig: &Signals) -> Vec<f64> {
    let kin = model.kinematic_truth(p).unwrap();
    let mut s = sig.clone();
    let tool = model.tool_state(p, &kin, joints, &mut s, None).unwrap();
    let pred = model.tracker(p, &tool, &mut s).unwrap();
    let y = pred.measured_point();
    vec![y.x, y.y, y.z, pred.measured_range()]
}

/// The example cells, plus the UR5 with a tool offset (a tool-frame term the joint offsets turn)
/// and a two-link URDF arm (link lengths along the URDF origins).
fn jacobian_cells() -> Vec<(String, Cell)> {
    let mut cells: Vec<(String, Cell)> = CELLS
        .iter()
        .map(|n| (n.to_string(), common::validate(&example_with_tracker(n))))
        .collect();
    let text = common::edited_example("serial_arm_ur5.yaml", "  - id: thermal_growth\n", "  - {id: tool_offset, params: {dx: 0.2 mm, dy: -0.1 mm, dz: 0.3 mm}}\n  - id: thermal_growth\n");
    cells.push((
        "ur5 + tool_offset".into(),
        Cell::from_yaml_str(&text, "ur5_tool_offset.yaml").unwrap(),
    ));
    // the XFYZ cell with a time offset (readings during moves have a velocity), compliance under
    // a load, and the part misaligned and expanding
    let extra = "  - {id: time_offset, params: {latency: 4 ms}}\n  - {id: compliance, options: {extension_axis: z}, params: {translational: 2e-8 m/N, rotational: 3e-8 rad/(N m), bending: 1e-7 1/(N m^2)}}\n  - {id: frame_misalignment, options: {origin: [400 mm, 300 mm, 0 mm]}, params: {rx: 20 urad, ry: -15 urad, rz: 60 urad, tx: 8 um, ty: -5 um, tz: 3 um}}\n  - {id: workpiece_expansion, options: {sensor: table, clamp: [100 mm, 100 mm, 0 mm]}, params: {alpha: 23e-6 1/K}}\n  - id: thermal_scale\n";
    let text = common::edited_example("xfyz_shift.yaml", "  - id: thermal_scale\n", extra).replace(
        "environment:\n",
        "environment:\n  load_force: [0 N, 0 N, -150 N]\n",
    );
    cells.push((
        "xfyz + time_offset, compliance, workpiece terms".into(),
        Cell::from_yaml_str(&text, "xfyz_more.yaml").unwrap_or_else(|e| panic!("{e}")),
    ));
    let dir = std::env::temp_dir().join(format!(
        "metrocell-twin-shared-model-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("two_link.urdf"), common::TWO_LINK_URDF).unwrap();
    let text = std::fs::read_to_string(common::cell_path("serial_arm_ur5.yaml")).unwrap();
    let (m0, m1) = (
        text.find("  serial_arm:\n").unwrap(),
        text.find("\nsensors:").unwrap(),
    );
    let (p0, p1) = (
        text.find("  joints:\n").unwrap(),
        text.find("  feed_rate:").unwrap(),
    );
    let t0 = text.find("\nterms:").unwrap();
    let arm = "  serial_arm:\n    urdf: {path: two_link.urdf, root_link: base, tip_link: tip}\n";
    let program = "  joints:\n    - [10 deg, 20 deg]\n    - [30 deg, 60 deg]\n";
    let terms = "\nterms:\n  - {id: joint_offset, options: {joints: 2}, params: {q1: 0.1 mrad, q2: 0.5 mrad}}\n  - {id: link_length, options: {links: 3}, params: {l1: 0.1 mm, l2: -0.2 mm, l3: 0.2 mm}}\n  - {id: tool_offset, params: {dx: 0.2 mm, dy: -0.1 mm, dz: 0.3 mm}}\n";
    std::fs::write(
        dir.join("cell.yaml"),
        format!(
            "{}{}{}{}{}{}",
            &text[..m0],
            arm,
            &text[m1..p0],
            program,
            &text[p1..t0],
            terms
        ),
    )
    .unwrap();
    cells.push((
        "two-link URDF arm".into(),
        Cell::from_path(dir.join("cell.yaml")).unwrap_or_else(|e| panic!("{e}")),
    ));
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
            let mut j = DMatrix::zeros(TRACKER_ROWS, model.param_count());
            let mut work = Workspace::new(&model);
            let pred = model
                .tracker_jacobian(&p, &kin, &tt.joints, &mut sig.clone(), &mut work, &mut j)
                .unwrap();
            let y = reading(&model, &p, &tt.joints, &sig);
            assert_eq!(
                y[3],
                pred.measured_range(),
                "{name}: the Jacobian's prediction is the model's"
            );
            common::check_columns(
                &format!("{name} tracker t = {}", s.t),
                &names,
                &p,
                &j,
                |q| reading(&model, q, &tt.joints, &sig),
            );
            checked += 1;
        }
        assert!(checked >= 3, "{name}: {checked} readings checked");
        // every term of the cell has a parameter in the Jacobian
        assert!(
            names.iter().any(|n| n.starts_with("tracker_pose."))
                && names.iter().any(|n| n.starts_with("refraction.")),
            "{name}: {names:?}"
        );
        let kinematic = ["delta_", "joint_offset.", "link_length."];
        if name.contains("delta") || name.contains("arm") || name.contains("ur5") {
            assert!(
                names
                    .iter()
                    .any(|n| kinematic.iter().any(|k| n.starts_with(k))),
                "{name}: no kinematic term in {names:?}"
            );
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
    let at = |n: &str| {
        setup
            .names
            .iter()
            .position(|x| x == n)
            .unwrap_or_else(|| panic!("{n} not in {:?}", setup.names))
    };
    assert!(
        !setup.free[at("positioning[y].c0")]
            && setup.free[at("positioning[y].c1")]
            && setup.free[at("positioning[y].c2")]
    );
    assert!(setup.free[at("tracker_pose.tz")] && !setup.free[at("tracker_pose.alpha")]);
    assert!(
        setup.free[at("squareness[xy].s")],
        "terms without settings stay free"
    );
    assert_eq!(
        setup.priors[at("positioning[y].c0")],
        Some(metrocell_model::Prior {
            value: 0.0,
            sigma: 5e-6
        })
    );
    assert_eq!(setup.priors.iter().filter(|p| p.is_some()).count(), 1);
    // fixed: positioning[y].c0 and tracker_pose's three angles
    assert_eq!(setup.free.iter().filter(|f| !**f).count(), 4);

    for (bad, needles) in [
        (
            "\nestimation:\n  \"positioning[q]\": {free: [c0]}\n",
            vec![
                "estimation.positioning[q]",
                "positioning[y]",
                "tracker_pose",
            ],
        ),
        (
            "\nestimation:\n  \"positioning[y]\": {free: [c7]}\n",
            vec![
                "estimation.positioning[y].free",
                "c7",
                "allowed: c0, c1, c2",
            ],
        ),
        (
            "\nestimation:\n  \"positioning[y]\": {priors: {c0: {value: 0 um, sigma: 0 um}}}\n",
            vec!["estimation.positioning[y].priors.c0", "σ > 0"],
        ),
        (
            "\nestimation:\n  tracker_pose: {priors: {tx: {value: 3 K, sigma: 1 mm}}}\n",
            vec!["estimation.tracker_pose.priors.tx.value", "`K`"],
        ),
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
    let text = common::edited_example(
        "xfyz_shift.yaml",
        "  - id: squareness\n",
        "  - {id: tool_offset, params: {dx: 0.1 mm, dy: 0 mm, dz: -0.2 mm}}\n  - id: squareness\n",
    );
    let misaligned = "  - {id: frame_misalignment, params: {rx: 0 rad, ry: 0 rad, rz: 50 urad, tx: 5 um, ty: 0 um, tz: -4 um}}\n  - id: squareness\n";
    let with_misalignment = text.replace("  - id: squareness\n", misaligned);
    let five_axis =
        common::edited_example("five_axis_table.yaml", "  - id: squareness\n", misaligned);
    // xfyz + tool_offset: y: c0 ∥ d, c0 ∥ T, d ∥ T; x, z: d ∥ T. With the part misaligned, per axis
    // also d ∥ t, t ∥ T (and on y c0 ∥ t): 12. Five-axis: only t ∥ T (the table turns the rest).
    let cells = [
        (
            "xfyz + tool_offset",
            Cell::from_yaml_str(&text, "xfyz_tool.yaml").unwrap(),
            5,
        ),
        (
            "xfyz + tool_offset + frame_misalignment",
            Cell::from_yaml_str(&with_misalignment, "xfyz_misaligned.yaml").unwrap(),
            12,
        ),
        (
            "xfyz_shift",
            common::validate(&common::example_file("xfyz_shift.yaml")),
            1,
        ),
        (
            "five_axis_table",
            common::validate(&common::example_file("five_axis_table.yaml")),
            0,
        ),
        (
            "five_axis_table + frame_misalignment",
            Cell::from_yaml_str(&five_axis, "five_axis_misaligned.yaml").unwrap(),
            3,
        ),
    ];
    for (name, cell, expected) in cells {
        let sim = Simulation::new(cell, 6.0, 2).unwrap();
        let model = sim.forward_model();
        let names = model.param_names();
        let pairs = model.parallel_pairs();
        assert_eq!(
            pairs.len(),
            expected,
            "{name}: {:?}",
            pairs
                .iter()
                .map(|p| (&names[p.a], &names[p.b]))
                .collect::<Vec<_>>()
        );
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        let mut work = Workspace::new(&model);
        let mut j = DMatrix::zeros(TRACKER_ROWS, model.param_count());
        for (s, tt) in tracker_readings(&sim).iter().step_by(13) {
            model
                .tracker_jacobian(
                    &p,
                    &kin,
                    &tt.joints,
                    &mut reading_signals(&sim, s),
                    &mut work,
                    &mut j,
                )
                .unwrap();
            for pair in &pairs {
                let (a, b) = (j.column(pair.a), j.column(pair.b));
                assert!(
                    (a - b * pair.sign).amax() <= 1e-9 * a.amax(),
                    "{name}: {} vs {}: {a} vs {b}",
                    names[pair.a],
                    names[pair.b]
                );
                assert!(
                    a.amax() > 0.1,
                    "{name}: {} moves the reading",
                    names[pair.a]
                );
            }
        }
    }
}

/// Probe hits and camera frame requests with their truth.
fn probe_hits(sim: &Simulation) -> Vec<ProbeHitSample> {
    sim.samples()
        .filter_map(|s| {
            if let Sample::ProbeHit(h) = s {
                Some(h)
            } else {
                None
            }
        })
        .collect()
}

fn camera_requests(sim: &Simulation) -> Vec<(CameraFrameRequest, Vec<f64>)> {
    sim.samples_with_truth()
        .filter_map(|(s, t)| match (s, t) {
            (Sample::CameraFrameRequest(r), SampleTruth::CameraFrameRequest { joints, .. }) => {
                Some((r, joints))
            }
            _ => None,
        })
        .collect()
}

/// The commanded joint vector of the signals (cartesian and delta: the axis positions).
fn axes(sig: &Signals) -> Vec<f64> {
    sig.axis_position
        .iter()
        .map(|v| v.expect("axis position"))
        .collect()
}

/// Workpiece-frame terms for the quick demo (its thermocouple `x_left` sits on the table).
const WORKPIECE_TERMS: &str = "  - {id: frame_misalignment, options: {origin: [200 mm, 150 mm, 0 mm]}, params: {rx: 20 urad, ry: -15 urad, rz: 60 urad, tx: 8 um, ty: -5 um, tz: 3 um}}\n  - {id: workpiece_expansion, options: {sensor: x_left, clamp: [200 mm, 150 mm, 0 mm]}, params: {alpha: 23e-6 1/K}}\n";

/// A Brown–Conrady lens for the quick demo's camera.
const DEMO_LENS: &str = "    intrinsics: {width: 2048, height: 1536, fx: 2600 px, fy: 2605 px, cx: 1023.5 px, cy: 767.5 px, model: plumb_bob, distortion: [-0.12, 0.05, 0.0007, -0.0004, -0.01]}\n";

/// Cells with a probe or a camera: the example cells that have one, the quick demo with
/// workpiece-frame terms and a Brown–Conrady lens, a delta with a probe, the UR5 with a camera
/// on its flange (joint offsets turn it).
fn instrument_cells() -> Vec<(String, Cell)> {
    let mut cells: Vec<(String, Cell)> = [
        "quick_demo.yaml",
        "xfyz_shift.yaml",
        "five_axis_table.yaml",
        "delta_printer.yaml",
    ]
    .iter()
    .map(|n| (n.to_string(), common::validate(&common::example_file(n))))
    .collect();
    let text = common::edited_example(
        "quick_demo.yaml",
        "    delay: 1 s\n",
        &format!("    delay: 1 s\n{DEMO_LENS}"),
    );
    let text = text.replace(
        "  - id: thermal_scale\n",
        &format!("{WORKPIECE_TERMS}  - id: thermal_scale\n"),
    );
    cells.push((
        "quick_demo + workpiece terms + lens".into(),
        Cell::from_yaml_str(&text, "demo_workpiece.yaml").unwrap(),
    ));
    let probe = "  probe:\n    directions: [[1, 0, 0], [0, -1, 0], [0, 0, -1], [0.6, 0.8, 0]]\n    hit_interval: 0.3 s\n    noise: 0.4 um\n    pretravel: {options: {lobes: 3}, params: {mean: 8 um, lobe_cos: -2 um, lobe_sin: 1.5 um, vertical: 4 um}}\n  camera:\n";
    let text = common::edited_example("delta_printer.yaml", "  camera:\n", probe);
    cells.push((
        "delta + probe".into(),
        Cell::from_yaml_str(&text, "delta_probe.yaml").unwrap(),
    ));
    let camera = "sensors:\n  camera:\n    mount: {translation: [0 mm, 40 mm, 60 mm], euler_xyz: [0 deg, 0 deg, 90 deg]}\n    delay: 0.5 s\n";
    let text = common::edited_example("serial_arm_ur5.yaml", "sensors:\n", camera);
    cells.push((
        "ur5 + camera".into(),
        Cell::from_yaml_str(&text, "ur5_camera.yaml").unwrap(),
    ));
    cells
}

#[test]
fn noise_free_probe_hits_and_camera_readings_are_the_models_predictions_bit_for_bit() {
    let (mut probes, mut frames) = (0, 0);
    for (name, mut cell) in instrument_cells() {
        if let Some(p) = cell.probe.as_mut() {
            p.noise = 0.0;
        }
        let sim = Simulation::new(cell, 40.0, 7).unwrap();
        let model = sim.forward_model();
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        for h in probe_hits(&sim) {
            let mut sig = sim.signals_at(h.t);
            let hit = ProbeTarget {
                surface: h.nominal,
                approach: h.direction,
                stylus_radius: 0.0,
            };
            let pred = model
                .probe_hit(None, &p, &kin, &axes(&sig), &mut sig, &hit)
                .unwrap();
            assert_eq!(pred.centre, h.recorded, "{name} t = {}: probe reading", h.t);
            assert!(
                pred.pretravel.norm() > 1e-6,
                "{name}: the pretravel is in the reading"
            );
            probes += 1;
        }
        let spec = sim.cell().camera.clone();
        for (r, joints) in camera_requests(&sim) {
            let spec = spec.as_ref().unwrap();
            let mut sig = sim.signals_at(r.t);
            let tool = model.tool_state(&p, &kin, &joints, &mut sig, None).unwrap();
            let (nominal, truth) = model.camera_pose(None, &tool).unwrap();
            assert_eq!(
                (
                    truth.translation.vector,
                    truth.rotation.to_rotation_matrix().into_inner()
                ),
                (r.position, r.rotation),
                "{name} t = {}: camera pose",
                r.t
            );
            assert_eq!(
                nominal.translation.vector, r.nominal_position,
                "{name} t = {}",
                r.t
            );
            let corners = r
                .corners
                .as_ref()
                .expect("a pinhole + Brown–Conrady lens has predicted corners");
            let features = spec.plate.corners_in_workpiece(&nominal);
            assert_eq!(corners.len(), 16);
            for (f, c) in features.iter().zip(corners) {
                let pred = model.camera(None, &p, &tool, &mut sig, f).unwrap();
                assert_eq!(pred.pixel, *c, "{name} t = {}: corner pixel", r.t);
                // every corner is on the image
                let lens = spec.lens();
                assert!(
                    c.x > 0.0 && c.y > 0.0 && c.x < lens.width as f64 && c.y < lens.height as f64,
                    "{name}: corner {c} off the image"
                );
            }
            frames += 1;
        }
    }
    println!("{probes} probe hits, {frames} camera frames");
    assert!(
        probes >= 60 && frames >= 15,
        "{probes} probe hits, {frames} frames"
    );
}

#[test]
fn noisy_probe_residuals_over_the_stated_sigma_are_standard_normal() {
    let sim = Simulation::new(
        common::validate(&common::example_file("quick_demo.yaml")),
        1800.0,
        9,
    )
    .unwrap();
    let model = sim.forward_model();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let mut z = Vec::new();
    for h in probe_hits(&sim) {
        let mut sig = sim.signals_at(h.t);
        let pred = model
            .probe_hit(
                None,
                &p,
                &kin,
                &axes(&sig),
                &mut sig,
                &ProbeTarget {
                    surface: h.nominal,
                    approach: h.direction,
                    stylus_radius: 0.0,
                },
            )
            .unwrap();
        let sigma = h.covariance[(0, 0)].sqrt();
        assert_eq!(h.covariance, nalgebra::Matrix3::identity() * sigma * sigma);
        z.extend((h.recorded - pred.centre).iter().map(|r| r / sigma));
    }
    let (mean, std) = common::mean_std(&z);
    let n = z.len() as f64;
    println!("probe: n = {n}, mean {mean:.4}, std {std:.4}");
    assert!(n >= 4000.0, "n = {n}");
    assert!(mean.abs() < 3.0 / n.sqrt(), "mean {mean}");
    assert!((std - 1.0).abs() < 0.05, "std {std}");
}

/// Instrument terms of a cell plus a `camera_scale` (the twin's camera has none: a scale error
/// belongs to the detector), so the camera Jacobian has that column too.
fn with_camera_scale(sim: &Simulation) -> metrocell_physics::model::TermModel {
    let mut m = sim.instrument_terms().clone();
    if sim.cell().camera.is_some() {
        let cfg = metrocell_physics::TermConfig {
            id: "camera_scale".into(),
            options: Default::default(),
            params: [(
                "scale".to_string(),
                metrocell_physics::config::ConfigValue::Number(4e-4),
            )]
            .into_iter()
            .collect(),
            use_defaults: false,
        };
        m.push(metrocell_physics::configure(&cfg).unwrap()).unwrap();
    }
    m
}

#[test]
fn probe_and_camera_jacobians_match_central_differences() {
    for (name, cell) in instrument_cells() {
        let sim = Simulation::new(cell, 40.0, 3).unwrap();
        let instruments = with_camera_scale(&sim);
        let model = sim.cell().forward_model(&instruments).unwrap();
        let names = model.param_names();
        let p = model.params();
        let kin = model.kinematic_truth(&p).unwrap();
        let mut work = Workspace::new(&model);
        let mut columns = 0;
        for h in probe_hits(&sim).iter().step_by(5).take(4) {
            let mut sig = sim.signals_at(h.t);
            // a probing move at 5 mm/s (so a time offset would show)
            sig.axis_velocity = [
                Some(h.direction.x * 5e-3),
                Some(h.direction.y * 5e-3),
                Some(h.direction.z * 5e-3),
            ];
            let q = axes(&sig);
            let hit = ProbeTarget {
                surface: h.nominal,
                approach: h.direction,
                stylus_radius: 1.5e-3,
            };
            let mut j = DMatrix::zeros(PROBE_ROWS, model.param_count());
            let pred = model
                .probe_jacobian(
                    None,
                    &p,
                    &kin,
                    &q,
                    &mut sig.clone(),
                    &hit,
                    &mut work,
                    &mut j,
                )
                .unwrap();
            let probe = |x: &[f64]| {
                let kin = model.kinematic_truth(x).unwrap();
                let c = model
                    .probe_hit(None, x, &kin, &q, &mut sig.clone(), &hit)
                    .unwrap()
                    .centre;
                vec![c.x, c.y, c.z]
            };
            assert_eq!(
                probe(&p),
                pred.centre.as_slice(),
                "{name}: the Jacobian's prediction is the model's"
            );
            columns +=
                common::check_columns(&format!("{name} probe t = {}", h.t), &names, &p, &j, probe);
        }
        let spec = sim.cell().camera.clone();
        for (r, joints) in camera_requests(&sim).iter().take(3) {
            let plate = spec.as_ref().unwrap().plate;
            let sig = sim.signals_at(r.t);
            let nominal = Isometry3::from_parts(
                r.nominal_position.into(),
                nalgebra::UnitQuaternion::from_matrix(&r.nominal_rotation),
            );
            for f in plate.corners_in_workpiece(&nominal).iter().step_by(5) {
                let mut j = DMatrix::zeros(CAMERA_ROWS, model.param_count());
                let pred = model
                    .camera_jacobian(
                        None,
                        &p,
                        &kin,
                        joints,
                        &mut sig.clone(),
                        f,
                        &mut work,
                        &mut j,
                    )
                    .unwrap();
                let camera = |x: &[f64]| {
                    let kin = model.kinematic_truth(x).unwrap();
                    let mut s = sig.clone();
                    let tool = model.tool_state(x, &kin, joints, &mut s, None).unwrap();
                    let c = model.camera(None, x, &tool, &mut s, f).unwrap();
                    vec![
                        c.pixel.x,
                        c.pixel.y,
                        c.measured_point.x,
                        c.measured_point.y,
                        c.measured_point.z,
                    ]
                };
                let y = camera(&p);
                assert_eq!(
                    (y[0], y[1], y[4]),
                    (pred.pixel.x, pred.pixel.y, pred.measured_point.z),
                    "{name}: the Jacobian's prediction is the model's"
                );
                let what = format!("{name} camera t = {}", r.t);
                // pixel rows and metre rows separately (each against its own scale)
                columns += common::check_columns(
                    &format!("{what} pixels"),
                    &names,
                    &p,
                    &j.rows(0, 2).into_owned(),
                    |x| camera(x)[..2].to_vec(),
                );
                columns += common::check_columns(
                    &format!("{what} camera point"),
                    &names,
                    &p,
                    &j.rows(2, 3).into_owned(),
                    |x| camera(x)[2..].to_vec(),
                );
            }
        }
        assert!(columns > 0, "{name}: nothing checked");
        // the instrument terms are in the model and move its readings
        for label in [
            "probe_pretravel.mean",
            "lens_distortion.k1",
            "camera_scale.scale",
            "frame_misalignment.rz",
            "workpiece_expansion[x_left].alpha",
        ] {
            if let Some(c) = names.iter().position(|n| n == label) {
                println!("{name}: {label} in the model");
                assert!(c < p.len());
            }
        }
    }
}

/// Only linear machine terms (the geometric series, squareness): what a kept target needs.
const LINEAR_XFYZ_TERMS: &str = "  - {id: squareness, options: {pair: xy}, params: {s: 20 urad}}\n  - {id: positioning, options: {axis: y, order: 2, travel: [0 mm, 500 mm]}, params: {c0: 1 um, c1: 6 um, c2: -2 um}}\n  - {id: straightness, options: {axis: x, direction: z, order: 3, travel: [0 mm, 800 mm]}, params: {c0: 0 um, c1: 2 um, c2: -3 um, c3: 1 um}}\n  - {id: angular, options: {axis: x, about: z, lever_axes: [y, z], abbe_offset: [0 m, 0.05 m, -0.15 m], order: 2, travel: [0 mm, 800 mm]}, params: {c0: 5 urad, c1: -8 urad, c2: 3 urad}}\n  - {id: angular, options: {axis: z, about: x, order: 1, travel: [0 mm, 400 mm]}, params: {c0: 0 urad, c1: 4 urad}}\n";
const LINEAR_FIVE_AXIS_TERMS: &str = "  - {id: squareness, options: {pair: xy}, params: {s: 60 urad}}\n  - {id: positioning, options: {axis: y, order: 1, travel: [0 mm, 1150 mm]}, params: {c0: 0 um, c1: 20 um}}\n  - {id: straightness, options: {axis: x, direction: y, order: 2}, params: {c0: 1 um, c1: 3 um, c2: -2 um}}\n";

/// Example cell `file` with its `terms:` (the file's last section) replaced by `terms`.
fn with_terms(file: &str, terms: &str) -> Cell {
    let text = std::fs::read_to_string(common::cell_path(file)).unwrap();
    let t0 = text.find("\nterms:").unwrap();
    Cell::from_yaml_str(&format!("{}\nterms:\n{terms}", &text[..t0]), file)
        .unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// A tracker reading from a kept target (crates/model `linear_target`: P₀ and A formed once,
/// packed to the rows that are not zero) is the model's full evaluation to round-off, at
/// parameters far from those it was kept at, on a cartesian and a five-axis machine; the
/// prediction without the Jacobian is the one with it, bit for bit. A model with a term that is
/// not linear (thermal, a delta's or an arm's kinematics) keeps nothing and says why.
#[test]
fn kept_linear_targets_give_the_models_readings_and_jacobians() {
    use metrocell_model::KeptLayout;
    use nalgebra::Matrix3;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    for (name, cell) in [
        ("xfyz", with_terms("xfyz_shift.yaml", LINEAR_XFYZ_TERMS)),
        (
            "five-axis",
            with_terms("five_axis_table.yaml", LINEAR_FIVE_AXIS_TERMS),
        ),
    ] {
        let sim = Simulation::new(cell, 12.0, 3).unwrap();
        let model = sim.forward_model();
        let n = model.param_count();
        let machine = model.machine_terms.param_specs().len();
        assert_eq!(model.linear_target_columns(), Some(machine), "{name}");
        let full_len = model.linear_target_len().unwrap();
        let names = model.param_names();
        let mut checked = 0;
        for (s, tt) in tracker_readings(&sim).iter().step_by(29) {
            let sig = reading_signals(&sim, s);
            let mut work = Workspace::new(&model);
            let mut full = vec![0.0; full_len];
            model
                .linear_target(&tt.joints, &mut sig.clone(), &mut work, &mut full)
                .unwrap();
            let layout = KeptLayout::empty(machine).widened(&full);
            assert!(
                layout.covers(&full) && layout.values_per_reading() < full_len,
                "{name}: {} of {full_len} values kept",
                layout.values_per_reading()
            );
            let mut kept = vec![0.0; layout.values_per_reading()];
            layout.pack(&full, &mut kept);
            // far from where A was formed: every machine parameter ±30 µm or µrad, the pose moved
            let mut p = model.params();
            for (k, v) in p.iter_mut().enumerate() {
                if k < machine {
                    *v = rng.random_range(-30e-6..30e-6);
                } else if names[k].starts_with("tracker_pose.t") {
                    *v += rng.random_range(-1e-3..1e-3);
                }
            }
            let kin = model.kinematic_truth(&p).unwrap();
            let mut reference = DMatrix::zeros(TRACKER_ROWS, n);
            let want = model
                .tracker_jacobian(
                    &p,
                    &kin,
                    &tt.joints,
                    &mut sig.clone(),
                    &mut work,
                    &mut reference,
                )
                .unwrap()
                .measured_point();
            let mut jac = DMatrix::from_element(3, n, f64::NAN);
            let columns: Vec<usize> = (0..n).collect();
            let got = model
                .tracker_point_jacobian_mapped_linear(
                    None,
                    &p,
                    &layout,
                    &kept,
                    &mut sig.clone(),
                    &mut work,
                    &Matrix3::identity(),
                    &columns,
                    |c, v| jac.set_column(c, &v),
                )
                .unwrap()
                .measured_point();
            assert!(
                (got - want).norm() <= 1e-12,
                "{name} t = {}: kept {got:?} vs model {want:?}",
                s.t
            );
            for c in 0..n {
                let (a, b) = (jac.column(c), reference.fixed_view::<3, 1>(0, c));
                assert!(
                    (a - b).norm() <= 1e-12 * b.norm() + 1e-15,
                    "{name} t = {}, {}: kept {:?} vs model {:?}",
                    s.t,
                    names[c],
                    a.as_slice(),
                    b.iter().collect::<Vec<_>>()
                );
            }
            let alone = model
                .tracker_linear(None, &p, &layout, &kept, &mut sig.clone(), &mut work)
                .unwrap()
                .measured_point();
            assert_eq!(alone, got, "{name}: the prediction without the Jacobian");
            checked += 1;
        }
        assert!(checked >= 3, "{name}: {checked} readings checked");
    }
    for name in [
        "xfyz_shift.yaml",
        "serial_arm_ur5.yaml",
        "delta_printer.yaml",
    ] {
        let sim = Simulation::new(common::validate(&example_with_tracker(name)), 12.0, 3).unwrap();
        let model = sim.forward_model();
        assert_eq!(model.linear_target_columns(), None, "{name}");
        let (s, tt) = &tracker_readings(&sim)[0];
        let mut out = vec![0.0; 3];
        let e = model
            .linear_target(
                &tt.joints,
                &mut reading_signals(&sim, s),
                &mut Workspace::new(&model),
                &mut out,
            )
            .unwrap_err();
        assert!(e.to_string().contains("not linear"), "{name}: {e}");
    }
}
