//! Cell files read as models to estimate (`CellModel`): what a model may leave out, what the
//! loader adds, the defaults of the parameter setup, and errors naming the file and the key.

mod common;

use common::{assert_mentions, cell_path};
use metrocell_twin::{Cell, CellModel};
use std::path::Path;

fn model(text: &str) -> Result<CellModel, String> {
    CellModel::from_yaml_str_in(text, "model.yaml", Path::new(".")).map_err(|e| e.to_string())
}

const MINIMAL: &str = r#"
name: minimal_model
machine:
  family: cartesian
  stacking: XFYZ
  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}
terms:
  - id: thermal_scale
    options: {axis: x, sensors: [{name: x_left, position: 0 m}, {name: x_right, position: 0.8 m}]}
    params: {alpha: 11.5e-6 1/K}
  - id: positioning
    options: {axis: y, order: 2}
    params: {c0: 0 um, c1: 0 um, c2: 0 um}
"#;

#[test]
fn every_example_cell_reads_as_a_model_with_the_twins_terms() {
    for f in [
        "quick_demo.yaml",
        "demo_shift.yaml",
        "xfyz_shift.yaml",
        "delta_printer.yaml",
        "five_axis_table.yaml",
        "serial_arm_ur5.yaml",
    ] {
        let m = CellModel::from_path(cell_path(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        let cell = Cell::from_path(cell_path(f)).unwrap();
        let twin_instruments = cell.instrument_terms().unwrap();
        let twin = cell.forward_model(&twin_instruments).unwrap();
        let fm = m.forward_model().unwrap();
        // same machine terms, same values; the twin always adds refraction, the model only when
        // the file gives a station or a beam offset, and an identity pose when it has no tracker;
        // both take the probe's pretravel; a camera's lens is the camera model's (not a term of
        // the model file)
        assert_eq!(m.machine_terms.params(), cell.terms.params(), "{f}");
        let has_station = cell
            .tracker
            .as_ref()
            .is_some_and(|t| t.station != Default::default());
        let names = fm.param_names();
        if cell.tracker.is_some() {
            assert!(m.declares_tracker, "{f}");
            let twin_names = twin.param_names();
            let expected: Vec<&String> = twin_names
                .iter()
                .filter(|n| {
                    (has_station || !n.starts_with("refraction"))
                        && !n.starts_with("lens_distortion")
                })
                .collect();
            assert_eq!(names.iter().collect::<Vec<_>>(), expected, "{f}");
            let tp = names.iter().position(|n| n == "tracker_pose.tx").unwrap();
            assert_eq!(
                fm.params()[tp..tp + 6],
                twin.params()[tp..tp + 6],
                "{f}: the tracker pose starts at the file's"
            );
        } else {
            assert!(!m.declares_tracker, "{f}");
            let tp = names
                .iter()
                .position(|n| n == "tracker_pose.tx")
                .expect("an identity pose is added");
            assert!(fm.params()[tp..tp + 6].iter().all(|v| *v == 0.0), "{f}");
            assert!(
                m.setup.free[tp..tp + 6].iter().all(|f| *f),
                "{f}: the added pose is free"
            );
        }
        // refraction is fixed unless the file frees it; everything else is free by default
        let twin_setup = cell.parameter_setup().unwrap();
        for (k, n) in names.iter().enumerate() {
            let in_twin = twin_setup
                .names
                .iter()
                .position(|t| t == n)
                .map(|i| twin_setup.free[i])
                .unwrap_or(true);
            assert_eq!(
                m.setup.free[k],
                !n.starts_with("refraction") && in_twin,
                "{f}: {n}"
            );
        }
    }
}

#[test]
fn a_model_needs_only_machine_and_terms() {
    let m = model(MINIMAL).unwrap();
    assert_eq!(m.machine_terms.terms.len(), 2);
    // thermal_scale reads x_left/x_right: not declared here, the recording provides them
    assert_eq!(
        m.forward_model().unwrap().param_names(),
        [
            "thermal_scale[x].alpha",
            "positioning[y].c0",
            "positioning[y].c1",
            "positioning[y].c2",
            "tracker_pose.tx",
            "tracker_pose.ty",
            "tracker_pose.tz",
            "tracker_pose.alpha",
            "tracker_pose.beta",
            "tracker_pose.delta"
        ]
    );
    assert!((m.forward_model().unwrap().params()[0] - 11.5e-6).abs() < 1e-18);
    // the same text is not a cell the twin can simulate, and it says what is missing
    let e = Cell::from_yaml_str(MINIMAL, "minimal.yaml")
        .unwrap_err()
        .to_string();
    assert_mentions(&e, &["environment", "is required to simulate"]);
}

#[test]
fn a_tracker_without_noise_specs_is_fine_for_a_model_not_for_the_twin() {
    let text = format!("{MINIMAL}sensors:\n  tracker:\n    pose: {{translation: [-1 m, 0.2 m, 0.5 m], euler_xyz: [0 deg, 0 deg, 30 deg]}}\n    warmup: {{offset: 0 um, amplitude: 20 um, time_constant: 30 min}}\n");
    let m = model(&text).unwrap();
    let fm = m.forward_model().unwrap();
    let names = fm.param_names();
    assert!(names.iter().any(|n| n == "tracker_warmup.amplitude"));
    assert!(
        !names.iter().any(|n| n.starts_with("refraction")),
        "no station, no beam offset: no refraction term"
    );
    let tx = names.iter().position(|n| n == "tracker_pose.tx").unwrap();
    assert!((fm.params()[tx] + 1.0).abs() < 1e-15);
    let full = format!("{text}environment:\n  ambient: {{mean: 20 degC}}\n  air: {{pressure: 101.3 kPa, humidity: 50}}\nprogram:\n  points: [[0 m, 0 m, 0 m]]\n  feed_rate: 10 mm/s\n  dwell: 1 s\n");
    let e = Cell::from_yaml_str(&full, "c.yaml")
        .unwrap_err()
        .to_string();
    assert_mentions(
        &e,
        &[
            "sensors.tracker.rate",
            "is required to simulate the tracker",
        ],
    );
}

#[test]
fn estimation_settings_and_refraction_defaults() {
    let text = std::fs::read_to_string(cell_path("quick_demo.yaml")).unwrap();
    let m = CellModel::from_yaml_str_in(&text, "q.yaml", Path::new(".")).unwrap();
    let names = m.forward_model().unwrap().param_names();
    let k = names
        .iter()
        .position(|n| n == "refraction.path_temperature_offset")
        .expect("the demo has a station");
    assert!(!m.setup.free[k]);
    let freed = format!("{text}\nestimation:\n  refraction: {{free: [path_temperature_offset]}}\n  backlash[x]: {{free: []}}\n  \"thermal_scale[x]\": {{priors: {{alpha: {{value: 11.5e-6 1/K, sigma: 1e-6 1/K}}}}}}\n");
    let m = CellModel::from_yaml_str_in(&freed, "q.yaml", Path::new(".")).unwrap();
    assert!(m.setup.free[k] && !m.setup.free[k + 1]);
    let b = names
        .iter()
        .position(|n| n == "backlash[x].reversal")
        .unwrap();
    assert!(!m.setup.free[b]);
    let a = names
        .iter()
        .position(|n| n == "thermal_scale[x].alpha")
        .unwrap();
    let p = m.setup.priors[a].unwrap();
    assert!((p.value - 11.5e-6).abs() < 1e-18 && (p.sigma - 1e-6).abs() < 1e-18);
}

#[test]
fn uncertainties_of_a_previous_fit_are_read_and_checked() {
    let text = format!("{MINIMAL}uncertainty:\n  \"thermal_scale[x]\": {{alpha: 0.4e-6 1/K}}\n  \"positioning[y]\": {{c1: 1.5 um}}\n");
    let u = model(&text).unwrap().uncertainty().unwrap();
    assert!((u["thermal_scale[x].alpha"] - 0.4e-6).abs() < 1e-18);
    assert!((u["positioning[y].c1"] - 1.5e-6).abs() < 1e-18);
    let bad = format!("{MINIMAL}uncertainty:\n  \"positioning[y]\": {{c7: 1.5 um}}\n");
    assert_mentions(
        &model(&bad).unwrap_err(),
        &[
            "model.yaml",
            "uncertainty.positioning[y].c7",
            "positioning[y].c2",
        ],
    );
    let unit = format!("{MINIMAL}uncertainty:\n  \"positioning[y]\": {{c1: 1.5 urad}}\n");
    assert_mentions(&model(&unit).unwrap_err(), &["model.yaml", "c1", "urad"]);
}

#[test]
fn errors_name_the_file_and_the_key() {
    let e = model(&MINIMAL.replace("order: 2", "order: 2, colour: red")).unwrap_err();
    assert_mentions(&e, &["model.yaml", "terms[1]", "colour"]);
    let e = model(&MINIMAL.replace("stacking: XFYZ", "stacking: XFYQ")).unwrap_err();
    assert_mentions(&e, &["model.yaml", "machine.stacking"]);
    let e = model(&MINIMAL.replace("machine:", "machin:")).unwrap_err();
    assert_mentions(&e, &["model.yaml", "machin"]);
    let e = model(&format!(
        "{MINIMAL}estimation:\n  \"positioning[z]\": {{free: [c1]}}\n"
    ))
    .unwrap_err();
    assert_mentions(
        &e,
        &[
            "model.yaml",
            "estimation.positioning[z]",
            "labels",
            "positioning[y]",
        ],
    );
    let e = CellModel::from_path("/nonexistent/model.yaml")
        .unwrap_err()
        .to_string();
    assert_mentions(&e, &["/nonexistent/model.yaml"]);
}
