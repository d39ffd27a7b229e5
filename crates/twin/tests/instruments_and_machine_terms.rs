//! The shared model's instruments and the machine terms every instrument sees:
//! * two trackers and two cameras in one model are separate instruments: unique labels
//!   (`tracker_pose[lt1]`, …), each reading depends on its own terms only (its Jacobian is zero
//!   in the other instrument's columns and matches central differences in its own), a named
//!   tracker reads exactly what a model with only that tracker reads, and an unnamed request is
//!   refused when it is ambiguous;
//! * `time_offset` (d = −Δt·v) and `compliance` (d = F·(c₀ + c_θ e² + c_b e³)) are machine-frame
//!   terms of the tool: the twin's tool displacement is those equations evaluated on its signals,
//!   during moves (velocity ≠ 0) and at the probe's triggers.

mod common;

use metrocell_model::{
    CameraGeometry, ForwardModel, InstrumentPose, KinematicTruth, ProbeTarget, ToolState,
    Workspace, CAMERA_ROWS, TRACKER_ROWS,
};
use metrocell_physics::config::ConfigValue;
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, Signals, TermConfig};
use metrocell_twin::{Cell, Sample, SampleTruth, Simulation};
use nalgebra::{DMatrix, Vector3};

fn term(
    id: &str,
    instrument: Option<&str>,
    params: &[(&str, f64)],
) -> metrocell_physics::ConfiguredTerm {
    let options = instrument
        .map(|n| ("instrument".to_string(), ConfigValue::Text(n.into())))
        .into_iter()
        .collect();
    let params = params
        .iter()
        .map(|(k, v)| (k.to_string(), ConfigValue::Number(*v)))
        .collect();
    configure(&TermConfig {
        id: id.into(),
        options,
        params,
        use_defaults: true,
    })
    .unwrap_or_else(|e| panic!("{id}: {e}"))
}

fn pose(t: [f64; 3], e: [f64; 3]) -> [(&'static str, f64); 6] {
    [
        ("tx", t[0]),
        ("ty", t[1]),
        ("tz", t[2]),
        ("alpha", e[0]),
        ("beta", e[1]),
        ("delta", e[2]),
    ]
}

const LT1: ([f64; 3], [f64; 3]) = ([-1.2, 0.2, 0.6], [0.0, 0.0, 0.5]);
const LT2: ([f64; 3], [f64; 3]) = ([2.5, 1.4, 0.9], [0.01, -0.02, 3.0]);

fn camera(mount_x: f64) -> CameraGeometry {
    CameraGeometry {
        mount: InstrumentPose::from_euler_xyz(
            Vector3::new(mount_x, 0.0, 0.0),
            [std::f64::consts::PI, 0.0, 0.0],
        ),
        fx: 3000.0,
        fy: 3002.0,
        cx: 1023.5,
        cy: 767.5,
    }
}

/// Two trackers (lt1 with warm-up and refraction) and two cameras (cam1 with a scale, cam2 with
/// a lens) as one model's instrument terms.
fn two_trackers_and_two_cameras() -> TermModel {
    let mut instruments = TermModel::default();
    for t in [
        term("tracker_pose", Some("lt1"), &pose(LT1.0, LT1.1)),
        term(
            "tracker_warmup",
            Some("lt1"),
            &[
                ("offset", 3e-6),
                ("amplitude", 19e-6),
                ("time_constant", 1800.0),
            ],
        ),
        term(
            "refraction",
            Some("lt1"),
            &[
                ("path_temperature_offset", 0.4),
                ("path_pressure_offset", -30.0),
            ],
        ),
        term("tracker_pose", Some("lt2"), &pose(LT2.0, LT2.1)),
        term("camera_scale", Some("cam1"), &[("scale", 5e-4)]),
        term(
            "lens_distortion",
            Some("cam2"),
            &[
                ("k1", -0.1),
                ("k2", 0.04),
                ("k3", 0.0),
                ("p1", 5e-4),
                ("p2", -3e-4),
            ],
        ),
    ] {
        instruments.push(t).unwrap();
    }
    instruments
}

/// One reading of the model with two of each instrument: its parameters, kinematic truth,
/// joints, signals and tool state.
struct Reading<'r, 'm> {
    model: &'r ForwardModel<'m>,
    names: Vec<String>,
    p: Vec<f64>,
    kin: KinematicTruth,
    q: [f64; 3],
    sig: Signals,
    tool: ToolState,
}

#[test]
fn two_trackers_and_two_cameras_are_separate_instruments() {
    let cell = common::validate(&common::example_file("quick_demo.yaml"));
    let instruments = two_trackers_and_two_cameras();
    let model = ForwardModel::new(&cell.machine, &cell.terms, &instruments)
        .unwrap()
        .with_camera(Some("cam1"), camera(0.05))
        .unwrap()
        .with_camera(Some("cam2"), camera(-0.05))
        .unwrap();
    let names = model.param_names();
    for n in [
        "tracker_pose[lt1].tx",
        "tracker_pose[lt2].delta",
        "refraction[lt1].path_temperature_offset",
        "camera_scale[cam1].scale",
        "lens_distortion[cam2].k1",
    ] {
        assert!(names.contains(&n.to_string()), "{n} not in {names:?}");
    }
    assert_eq!(model.instruments().len(), 4);
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let q = [0.2, 0.15, 0.1];
    let mut sig = Signals {
        air_temperature: Some(20.5),
        air_pressure: Some(101_000.0),
        air_humidity: Some(45.0),
        time_since_power_on: Some(900.0),
        ..Signals::default()
    };
    sig.temperatures = cell
        .thermocouples
        .iter()
        .map(|t| (t.name.clone(), 20.7))
        .collect();
    model.set_motion(&mut sig, &q, &[0.0; 3], &[1.0; 3]);
    let tool = model
        .tool_state(&p, &kin, &q, &mut sig.clone(), None)
        .unwrap();
    let reading = Reading {
        model: &model,
        names,
        p,
        kin,
        q,
        sig,
        tool,
    };
    named_trackers_read_their_own_terms(&cell, &reading);
    let mut work = Workspace::new(&model);
    tracker_jacobians_are_separate(&reading, &mut work);
    cameras_are_separate(&reading, &mut work);
}

/// An unnamed reading is ambiguous with two trackers, an unknown name is refused, lt2 reads
/// what a model with only lt2's pose reads (bit for bit), and only lt1 has warm-up and
/// refraction.
fn named_trackers_read_their_own_terms(cell: &Cell, r: &Reading) {
    let (model, p, q, sig, tool) = (r.model, &r.p, &r.q, &r.sig, &r.tool);
    let err = model
        .tracker(p, tool, &mut sig.clone())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("lt1") && err.contains("lt2") && err.contains("name the instrument"),
        "{err}"
    );
    assert!(model
        .tracker_of(Some("lt3"), p, tool, &mut sig.clone())
        .unwrap_err()
        .to_string()
        .contains("no tracker named `lt3`"));

    // lt2 reads what a model with only lt2's pose (unnamed) reads, bit for bit
    let mut only = TermModel::default();
    only.push(term("tracker_pose", None, &pose(LT2.0, LT2.1)))
        .unwrap();
    let single = ForwardModel::new(&cell.machine, &cell.terms, &only).unwrap();
    let ps = single.params();
    let tool_single = single
        .tool_state(
            &ps,
            &single.kinematic_truth(&ps).unwrap(),
            q,
            &mut sig.clone(),
            None,
        )
        .unwrap();
    let lt2 = model
        .tracker_of(Some("lt2"), p, tool, &mut sig.clone())
        .unwrap();
    assert_eq!(
        lt2,
        single.tracker(&ps, &tool_single, &mut sig.clone()).unwrap()
    );
    let lt1 = model
        .tracker_of(Some("lt1"), p, tool, &mut sig.clone())
        .unwrap();
    assert!(
        (lt1.point - lt2.point).norm() > 1.0
            && lt1.warmup > 3e-6
            && lt1.refraction != 0.0
            && lt2.warmup == 0.0
            && lt2.refraction == 0.0
    );
}

/// Each tracker's Jacobian: zero in the other's columns, central differences in its own.
fn tracker_jacobians_are_separate(r: &Reading, work: &mut Workspace) {
    let (model, p, kin, q, sig) = (r.model, &r.p, &r.kin, &r.q, &r.sig);
    let columns = |label: &str| model.term_columns(label).unwrap();
    for (me, other) in [("lt1", "tracker_pose[lt2]"), ("lt2", "tracker_pose[lt1]")] {
        let mut j = DMatrix::zeros(TRACKER_ROWS, model.param_count());
        model
            .tracker_jacobian_of(Some(me), p, kin, q, &mut sig.clone(), work, &mut j)
            .unwrap();
        let (start, len) = columns(other);
        assert_eq!(
            j.columns(start, len).amax(),
            0.0,
            "{me}: {other} does not move it"
        );
        let (start, len) = columns(&format!("tracker_pose[{me}]"));
        assert!(
            j.columns(start, len).amax() > 0.1,
            "{me}: its own pose moves it"
        );
        let reading = |x: &[f64]| {
            let mut s = sig.clone();
            let tool = model
                .tool_state(x, &model.kinematic_truth(x).unwrap(), q, &mut s, None)
                .unwrap();
            let r = model.tracker_of(Some(me), x, &tool, &mut s).unwrap();
            let y = r.measured_point();
            vec![y.x, y.y, y.z, r.measured_range()]
        };
        common::check_columns(&format!("tracker {me}"), &r.names, p, &j, reading);
    }
}

/// The cameras: cam1 carries the scale (metric point), cam2 the lens (pixels); an unnamed
/// reading is ambiguous; each camera's Jacobian is zero in the other's columns and matches
/// central differences in its own.
fn cameras_are_separate(r: &Reading, work: &mut Workspace) {
    let (model, p, kin, q, sig, tool) = (r.model, &r.p, &r.kin, &r.q, &r.sig, &r.tool);
    let columns = |label: &str| model.term_columns(label).unwrap();
    // a part feature 150 mm below the tool point, a little off the cameras' axes
    let feature = tool.nominal.translation.vector + Vector3::new(0.01, 0.02, -0.15);
    let cam1 = model
        .camera(Some("cam1"), p, tool, &mut sig.clone(), &feature)
        .unwrap();
    let cam2 = model
        .camera(Some("cam2"), p, tool, &mut sig.clone(), &feature)
        .unwrap();
    assert!(
        (cam1.measured_point - cam1.point * (1.0 + 5e-4)).norm() < 1e-15
            && cam1.distorted == cam1.normalised
    );
    assert!(cam2.measured_point == cam2.point && (cam2.distorted - cam2.normalised).norm() > 1e-5);
    assert!(model
        .camera(None, p, tool, &mut sig.clone(), &feature)
        .unwrap_err()
        .to_string()
        .contains("name the instrument"));
    for (me, other) in [
        ("cam1", "lens_distortion[cam2]"),
        ("cam2", "camera_scale[cam1]"),
    ] {
        let mut j = DMatrix::zeros(CAMERA_ROWS, model.param_count());
        model
            .camera_jacobian(
                Some(me),
                p,
                kin,
                q,
                &mut sig.clone(),
                &feature,
                work,
                &mut j,
            )
            .unwrap();
        let (start, len) = columns(other);
        assert_eq!(
            j.columns(start, len).amax(),
            0.0,
            "{me}: {other} does not move it"
        );
        let reading = |x: &[f64]| {
            let mut s = sig.clone();
            let tool = model
                .tool_state(x, &model.kinematic_truth(x).unwrap(), q, &mut s, None)
                .unwrap();
            let c = model.camera(Some(me), x, &tool, &mut s, &feature).unwrap();
            vec![
                c.pixel.x,
                c.pixel.y,
                c.measured_point.x,
                c.measured_point.y,
                c.measured_point.z,
            ]
        };
        common::check_columns(
            &format!("camera {me} pixels"),
            &r.names,
            p,
            &j.rows(0, 2).into_owned(),
            |x| reading(x)[..2].to_vec(),
        );
        common::check_columns(
            &format!("camera {me} point"),
            &r.names,
            p,
            &j.rows(2, 3).into_owned(),
            |x| reading(x)[2..].to_vec(),
        );
    }
}

#[test]
fn instance_names_are_checked_and_labels_stay_unique() {
    let bad = TermConfig {
        id: "tracker_pose".into(),
        options: [("instrument".to_string(), ConfigValue::Text("lt 1".into()))]
            .into_iter()
            .collect(),
        params: Default::default(),
        use_defaults: true,
    };
    let err = configure(&bad).unwrap_err().to_string();
    assert!(err.contains("instrument") && err.contains("lt 1"), "{err}");
    // two unnamed trackers are one label twice: refused
    let mut m = TermModel::default();
    m.push(term("tracker_pose", None, &pose(LT1.0, LT1.1)))
        .unwrap();
    assert!(m
        .push(term("tracker_pose", None, &pose(LT2.0, LT2.1)))
        .unwrap_err()
        .to_string()
        .contains("declared twice"));
    // a term named for another instrument makes a second tracker, which has no pose of its own
    m.push(term("tracker_warmup", Some("lt2"), &[])).unwrap();
    let cell = common::validate(&common::example_file("quick_demo.yaml"));
    let model = ForwardModel::new(&cell.machine, &cell.terms, &m).unwrap();
    assert_eq!(model.instruments().len(), 2);
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let mut sig = Signals {
        time_since_power_on: Some(60.0),
        ..Signals::default()
    };
    sig.temperatures = cell
        .thermocouples
        .iter()
        .map(|t| (t.name.clone(), 20.0))
        .collect();
    model.set_motion(&mut sig, &[0.1, 0.1, 0.1], &[0.0; 3], &[1.0; 3]);
    let tool = model
        .tool_state(&p, &kin, &[0.1, 0.1, 0.1], &mut sig, None)
        .unwrap();
    let err = model
        .tracker_of(Some("lt2"), &p, &tool, &mut sig)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("tracker `lt2`") && err.contains("tracker_pose"),
        "{err}"
    );
    assert!(
        model.tracker_of(None, &p, &tool, &mut sig).is_err(),
        "two trackers: the unnamed request is ambiguous"
    );
}

/// The quick demo with only `time_offset` and `compliance` as machine terms, under a load.
fn demo_with_latency_and_compliance() -> Cell {
    let text = std::fs::read_to_string(common::cell_path("quick_demo.yaml")).unwrap();
    let terms = text.find("\nterms:").unwrap();
    let text = format!(
        "{}\nterms:\n  - {{id: time_offset, params: {{latency: 6 ms}}}}\n  - {{id: compliance, options: {{extension_axis: z, extension_origin: 50 mm}}, params: {{translational: 2e-8 m/N, rotational: 3e-8 rad/(N m), bending: 1e-7 1/(N m^2)}}}}\n",
        &text[..terms]
    )
    .replace("environment:\n", "environment:\n  load_force: [10 N, -20 N, -150 N]\n");
    Cell::from_yaml_str(&text, "demo_latency.yaml").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn time_offset_and_compliance_displace_the_tool_as_their_equations_say() {
    let sim = Simulation::new(demo_with_latency_and_compliance(), 60.0, 4).unwrap();
    let model = sim.forward_model();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let force = Vector3::new(10.0, -20.0, -150.0);
    let expected = |s: &Signals| {
        let v = Vector3::new(
            s.axis_velocity[0].unwrap(),
            s.axis_velocity[1].unwrap(),
            s.axis_velocity[2].unwrap(),
        );
        let e = s.axis_position[2].unwrap() - 0.05;
        -v * 6e-3 + force * (2e-8 + 3e-8 * e * e + 1e-7 * e * e * e)
    };
    let (mut moving, mut still) = (0, 0);
    for (s, t) in sim.samples_with_truth() {
        let (Sample::Tracker(r), SampleTruth::Tracker(tt)) = (s, t) else {
            continue;
        };
        let sig = sim.signals_at(r.t);
        let want = expected(&sig);
        assert!(
            (tt.displacement - want).norm() <= 1e-15 + 1e-12 * want.norm(),
            "t = {}: d {} vs {want}",
            r.t,
            tt.displacement
        );
        let tool = model
            .tool_state(&p, &kin, &tt.joints, &mut sig.clone(), None)
            .unwrap();
        assert_eq!(tool.d, tt.displacement);
        if sig.axis_velocity.iter().any(|v| v.unwrap() != 0.0) {
            // feed 100 mm/s: 0.6 mm of lag, far above the compliance's µm
            assert!(want.norm() > 1e-4, "t = {}: {want}", r.t);
            moving += 1;
        } else {
            still += 1;
        }
    }
    assert!(
        moving >= 50 && still >= 50,
        "{moving} readings while moving, {still} at rest"
    );
    // at a probe trigger the machine stands: only the compliance displaces it
    let mut hits = 0;
    for s in sim.samples() {
        let Sample::ProbeHit(h) = s else { continue };
        let mut sig = sim.signals_at(h.t);
        let q: Vec<f64> = sig.axis_position.iter().map(|v| v.unwrap()).collect();
        let pred = model
            .probe_hit(
                None,
                &p,
                &kin,
                &q,
                &mut sig,
                &ProbeTarget {
                    surface: h.nominal,
                    approach: h.direction,
                    stylus_radius: 0.0,
                },
            )
            .unwrap();
        let e = q[2] - 0.05;
        let want = force * (2e-8 + 3e-8 * e * e + 1e-7 * e * e * e);
        assert!(
            (pred.machine - want).norm() <= 1e-12 * want.norm(),
            "{} vs {want}",
            pred.machine
        );
        assert!(
            (h.recorded - (h.nominal - want + pred.pretravel)).norm() < 6.0 * 0.5e-6,
            "probe reading = nominal − d + pretravel + noise"
        );
        hits += 1;
    }
    assert!(hits >= 20, "{hits} probe hits");
}
