//! `metrocell diagnose` end to end on bags: a `metrocell sim` recording with a concealed reversal
//! error (JSON to stdout, the report directory with the augmented model that reads back and its
//! HTML, the residual table); a numpy-made export (bags/independent, not the twin) through
//! `metrocell bag import`; and bad input (a missing bag, a model file that is not one) answered
//! with a message that names it.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::metrocell;

fn dir(name: &str) -> PathBuf {
    common::scratch("diagnose", name)
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// An XFYZ machine measured by a tracker every 10 minutes for an hour; `terms` are added.
fn cell(terms: &str) -> String {
    format!(
        r#"name: probe_cell
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}}
  tool_offset: [0 mm, 0 mm, -150 mm]
sensors:
  tracker:
    pose: {{translation: [-863.5 mm, 194.4 mm, 677.8 mm], euler_xyz: [0.03 deg, 0.03 deg, 59.47 deg]}}
    rate: 5 Hz
    range_noise: {{constant: 4 um, per_metre: 0.8 um/m}}
    angular_noise: 3 urad
    powered_on_before_start: 4 h
  thermocouples:
    - {{name: x_left, location: ambient, noise: 0.02 K, rate: 0.2 Hz}}
  machine_state: {{rate: 10 Hz}}
environment:
  ambient: {{mean: 20.4 degC, drift: 0.3 K/h}}
  air: {{pressure: 101.3 kPa, humidity: 45}}
program:
  grid:
    x: {{from: 0 mm, to: 800 mm, count: 5}}
    y: {{from: 0 mm, to: 500 mm, count: 3}}
    z: {{from: 0 mm, to: 400 mm, count: 3}}
  order: serpentine
  feed_rate: 60 mm/s
  dwell: 2 s
  cycle_interval: 10 min
  home: [0 mm, 0 mm, 400 mm]
terms:
  - id: squareness
    options: {{pair: xy}}
    params: {{s: 20 urad}}
{terms}"#
    )
}

#[test]
fn a_sim_bag_with_a_concealed_reversal_error() {
    let d = dir("sim");
    std::fs::write(
        d.join("truth.yaml"),
        cell("  - id: backlash\n    options: {axis: x}\n    params: {reversal: 12 um}\n"),
    )
    .unwrap();
    std::fs::write(d.join("model.yaml"), cell("")).unwrap();
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            "truth.yaml",
            "--duration",
            "1h",
            "--seed",
            "4",
            "-o",
            "bag",
            "--quiet",
        ],
        &d,
    );
    assert_eq!(code, 0, "sim: {out}{err}");
    let (code, out, err) = metrocell(
        &[
            "diagnose",
            "--model",
            "model.yaml",
            "bag",
            "--json",
            "-",
            "--report",
            "report",
            "--residuals",
            "residuals.csv",
        ],
        &d,
    );
    assert_eq!(code, 0, "diagnose: {err}");
    let json: serde_json::Value = serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("stdout is not the JSON ({e}): {out}"));
    let findings = json["findings"].as_array().unwrap();
    assert_eq!(findings.len(), 1, "{}", json["summary"]);
    assert_eq!(findings[0]["label"], "backlash[x]");
    let r = &findings[0]["parameters"]["reversal"];
    let (v, s) = (r["value"].as_f64().unwrap(), r["sigma"].as_f64().unwrap());
    assert!((v - 12e-6).abs() < 3.0 * s, "β = {v} ± {s}");
    assert!(
        json["after"]["heldout_rms_m"].as_f64().unwrap()
            < 1.2 * json["noise_rms_m"].as_f64().unwrap()
    );
    assert!(
        err.contains("reversal error on X"),
        "the summary goes to stderr with --json -: {err}"
    );
    // the augmented model: the term added with its fitted value, and it reads back
    let model = std::fs::read_to_string(d.join("report/model.yaml")).unwrap();
    assert!(
        model.contains("id: backlash") && model.contains("uncertainty:"),
        "{model}"
    );
    let back = metrocell_twin::CellModel::from_path(d.join("report/model.yaml"))
        .expect("the augmented model reads back");
    let k = back
        .machine_terms
        .terms
        .iter()
        .position(|t| t.term.label() == "backlash[x]")
        .expect("backlash in the model");
    assert!(
        (back.machine_terms.terms[k].params[0] - v).abs() < 0.05 * s.max(1e-9) + 1e-9,
        "written {} vs fitted {v}",
        back.machine_terms.terms[k].params[0]
    );
    let html = std::fs::read_to_string(d.join("report/index.html")).unwrap();
    assert!(
        html.contains("backlash[x]") && html.matches("<svg").count() >= 5,
        "report with its plots"
    );
    // the residual table: one row per record used, the documented columns
    let csv = std::fs::read_to_string(d.join("residuals.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for c in [
        "time",
        "position_x",
        "residual_x",
        "sigma_x",
        "approach_x",
        "temperature.x_left",
    ] {
        assert!(header.split(',').any(|h| h == c), "{c} not in {header}");
    }
    assert_eq!(
        csv.lines().count() - 1,
        json["records"]["used"].as_u64().unwrap() as usize
    );
}

#[test]
fn a_numpy_export_through_bag_import() {
    let python = std::env::var("METROCELL_PYTHON").expect("METROCELL_PYTHON must name a Python with numpy: this test runs the independent generator (bags/independent/make_exports.py)");
    let d = dir("numpy");
    let gen = repo().join("bags/independent/make_exports.py");
    let status = Command::new(python)
        .arg(&gen)
        .arg("--out")
        .arg(&d)
        .arg("--seed")
        .arg("2")
        .arg("--variants")
        .arg("scale")
        .status()
        .unwrap();
    assert!(status.success());
    let mapping = repo().join("bags/independent/mapping.yaml");
    let model = repo().join("bags/independent/model.yaml");
    let (code, out, err) = metrocell(
        &[
            "bag",
            "import",
            "scale.csv",
            "-o",
            "points",
            "--mapping",
            mapping.to_str().unwrap(),
        ],
        &d,
    );
    assert_eq!(code, 0, "import: {out}{err}");
    let (code, out, err) = metrocell(
        &[
            "diagnose",
            "--model",
            model.to_str().unwrap(),
            "points",
            "--json",
            "result.json",
        ],
        &d,
    );
    assert_eq!(code, 0, "diagnose: {out}{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("result.json")).unwrap()).unwrap();
    assert_eq!(json["findings"][0]["label"], "thermal_scale[x]", "{out}");
    let a = &json["findings"][0]["parameters"]["alpha"];
    let (v, s) = (a["value"].as_f64().unwrap(), a["sigma"].as_f64().unwrap());
    assert!((v - 12.5e-6).abs() < 3.0 * s, "α = {v} ± {s}");
    assert_eq!(json["findings"].as_array().unwrap().len(), 1, "{out}");
    assert!(
        out.contains("the X scale expands with the bed temperature"),
        "{out}"
    );
}

#[test]
fn bad_input_is_named() {
    let d = dir("bad");
    std::fs::write(d.join("model.yaml"), cell("")).unwrap();
    let (code, _, err) = metrocell(
        &[
            "diagnose",
            "--model",
            "model.yaml",
            "no_such_bag",
            "--json",
            "-",
        ],
        &d,
    );
    assert_eq!(code, 1);
    assert!(err.contains("no_such_bag"), "{err}");
    std::fs::write(
        d.join("broken.yaml"),
        "name: broken\nmachine: {family: cartesian}\n",
    )
    .unwrap();
    let (code, _, err) = metrocell(&["diagnose", "--model", "broken.yaml", "no_such_bag"], &d);
    assert_eq!(code, 1);
    assert!(
        err.contains("broken.yaml") && err.contains("stacking"),
        "{err}"
    );
}

/// Issue 32 item 1: the demo's diagnosis wrote the tracker warm-up it found as `- id:
/// tracker_warmup` under `terms:`, and calibrate, diagnose, compensate and sim refused the file.
/// The augmented model keeps it in `sensors.tracker.warmup` (a tracker without a pose: unknown,
/// registered from each recording) and every command that reads a model takes it.
#[test]
fn the_demos_augmented_model_is_a_model_every_command_takes() {
    let d = dir("demo_augmented");
    let cells = repo().join("launch-configs/cells");
    let (shift, model) = (cells.join("demo_shift.yaml"), cells.join("demo_model.yaml"));
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            shift.to_str().unwrap(),
            "--duration",
            "20min",
            "--no-camera-frames",
            "--seed",
            "1",
            "-o",
            "bag",
            "--quiet",
        ],
        &d,
    );
    assert_eq!(code, 0, "sim: {out}{err}");
    let (code, out, err) = metrocell(
        &[
            "diagnose",
            "--model",
            model.to_str().unwrap(),
            "bag",
            "--report",
            "d",
        ],
        &d,
    );
    assert_eq!(code, 0, "diagnose: {out}{err}");
    assert!(
        out.contains("1. tracker_warmup"),
        "the 20 min recording shows the warm-up:\n{out}"
    );
    let written = std::fs::read_to_string(d.join("d/model.yaml")).unwrap();
    assert!(
        !written.contains("id: tracker_warmup")
            && written.contains("  tracker: {warmup: {offset: "),
        "{written}"
    );
    assert!(
        written.contains("# - sensors.tracker has no pose"),
        "{written}"
    );
    for (what, args) in [
        (
            "calibrate",
            vec![
                "calibrate",
                "--model",
                "d/model.yaml",
                "bag",
                "-o",
                "c.yaml",
            ],
        ),
        (
            "diagnose",
            vec![
                "diagnose",
                "--model",
                "d/model.yaml",
                "bag",
                "--json",
                "again.json",
            ],
        ),
        (
            "compensate table",
            vec![
                "compensate",
                "table",
                "--model",
                "d/model.yaml",
                "-o",
                "tables",
                "--temperatures-from",
                "bag",
            ],
        ),
    ] {
        let (code, out, err) = metrocell(&args, &d);
        assert_eq!(code, 0, "{what} of the augmented model: {out}{err}");
    }
    let back = metrocell_twin::CellModel::from_path(d.join("c.yaml"))
        .expect("calibrate's output reads back");
    assert!(back
        .instrument_terms
        .terms
        .iter()
        .any(|t| t.term.label() == "tracker_warmup"));
    // the simulator needs the pose the model leaves out, and says so
    let (code, _, err) = metrocell(
        &[
            "sim",
            "--cell",
            "d/model.yaml",
            "--duration",
            "1min",
            "-o",
            "s",
            "--quiet",
        ],
        &d,
    );
    assert_ne!(code, 0);
    assert!(
        err.contains("`sensors.tracker.pose`: is required to simulate the tracker"),
        "{err}"
    );
}

/// Issue 32 item 1: an empirical correction has no catalog term, so no model file can hold it;
/// the augmented model says, as a comment, what was left out and why, and stays a model.
#[test]
fn an_empirical_correction_is_said_in_the_augmented_model_not_written_as_a_term() {
    let d = dir("empirical");
    let case = repo().join("bags/cases/case_20");
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            case.join("truth.yaml").to_str().unwrap(),
            "--duration",
            "2h",
            "--no-camera-frames",
            "--seed",
            "1",
            "-o",
            "bag",
            "--quiet",
        ],
        &d,
    );
    assert_eq!(code, 0, "sim: {out}{err}");
    let (code, out, err) = metrocell(
        &[
            "diagnose",
            "--model",
            case.join("model.yaml").to_str().unwrap(),
            "bag",
            "--report",
            "d",
        ],
        &d,
    );
    assert_eq!(code, 0, "diagnose: {out}{err}");
    assert!(
        out.contains("an empirical time correction"),
        "the case's z drift in time is corrected empirically:\n{out}"
    );
    let written = std::fs::read_to_string(d.join("d/model.yaml")).unwrap();
    // the comments, unwrapped
    let said: String = written
        .lines()
        .filter_map(|l| l.strip_prefix("# -").or_else(|| l.strip_prefix("#  ")))
        .collect::<Vec<_>>()
        .join(" ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    assert!(
        said.contains("left out: the empirical correction `empirical_time[z]`")
            && said.contains("No catalog term describes it, so no model file can hold it"),
        "{written}"
    );
    assert!(!written.contains("id: empirical"), "{written}");
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "d/model.yaml",
            "bag",
            "-o",
            "c.yaml",
        ],
        &d,
    );
    assert_eq!(code, 0, "calibrate of the augmented model: {out}{err}");
}
