//! The one rule for the instrument terms a loaded model carries (`instrument_terms` module
//! docs): which terms, in which order, which are fixed by default, and the registered-points
//! view the estimator node reads.

use std::path::Path;

use metrocell_model_file::CellModel;

const MACHINE: &str = r#"
name: rule
machine:
  family: cartesian
  stacking: XFYZ
  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}
terms:
  - id: positioning
    options: {axis: y, order: 1}
    params: {c0: 0 um, c1: 0 um}
"#;

fn model(extra: &str) -> CellModel {
    let text = format!("{MACHINE}{extra}");
    CellModel::from_yaml_str_in(&text, "rule.yaml", Path::new("."))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn labels(m: &CellModel) -> Vec<String> {
    m.instrument_terms
        .terms
        .iter()
        .map(|t| t.term.label())
        .collect()
}

fn free(m: &CellModel, prefix: &str) -> Vec<bool> {
    let fm = m.forward_model().unwrap();
    fm.param_names()
        .iter()
        .zip(&m.setup.free)
        .filter(|(n, _)| n.starts_with(prefix))
        .map(|(_, f)| *f)
        .collect()
}

const TRACKER: &str = r#"
sensors:
  tracker:
    pose: {translation: [-0.8 m, 0.2 m, 0.7 m], euler_xyz: [0 deg, 0 deg, 60 deg]}
    warmup: {offset: 1 um, amplitude: 5 um, time_constant: 30 min}
    station: {temperature_bias: 0.1 K}
  probe:
    directions: [[1, 0, 0]]
    hit_interval: 1 s
    noise: 1 um
    pretravel: {options: {lobes: 3}, params: {mean: 10 um, lobe_cos: 3 um, lobe_sin: 0 um, vertical: 5 um}}
estimation:
  positioning[y]: {free: [c0]}
  tracker_warmup: {free: [offset]}
"#;

#[test]
fn without_a_tracker_the_model_carries_an_identity_pose_only() {
    let m = model("");
    assert_eq!(labels(&m), ["tracker_pose"]);
    assert!(!m.declares_tracker);
    let fm = m.forward_model().unwrap();
    let k = fm
        .param_names()
        .iter()
        .position(|n| n == "tracker_pose.tx")
        .unwrap();
    assert_eq!(&fm.params()[k..k + 6], &[0.0; 6]);
}

#[test]
fn a_tracker_and_a_probe_give_pose_warmup_refraction_then_pretravel() {
    let m = model(TRACKER);
    assert_eq!(
        labels(&m),
        [
            "tracker_pose",
            "tracker_warmup",
            "refraction",
            "probe_pretravel"
        ]
    );
    // refraction is fixed unless `estimation.refraction` frees it; the rest as the file says
    assert_eq!(free(&m, "refraction."), [false, false]);
    assert_eq!(free(&m, "tracker_warmup."), [true, false, false]);
    let fm = m.forward_model().unwrap();
    let k = fm
        .param_names()
        .iter()
        .position(|n| n == "refraction.path_temperature_offset")
        .unwrap();
    assert_eq!(fm.params()[k], -0.1, "path air − station reading");
}

#[test]
fn registered_points_carry_the_identity_pose_fixed_and_the_machine_settings() {
    let m = model(TRACKER).for_registered_points().unwrap();
    assert_eq!(labels(&m), ["tracker_pose"]);
    let fm = m.forward_model().unwrap();
    assert_eq!(
        fm.param_names(),
        [
            "positioning[y].c0",
            "positioning[y].c1",
            "tracker_pose.tx",
            "tracker_pose.ty",
            "tracker_pose.tz",
            "tracker_pose.alpha",
            "tracker_pose.beta",
            "tracker_pose.delta"
        ]
    );
    assert_eq!(
        m.setup.free,
        [true, false, false, false, false, false, false, false]
    );
    assert_eq!(&fm.params()[2..], &[0.0; 6]);
}
