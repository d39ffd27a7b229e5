//! Issue 27 on the digital twin's recordings: `launch-configs/cells/mobile_manipulator.yaml` (a
//! lifting column and a 6R arm bending under gravity, a prism read by a levelled total station
//! from three setups, accelerometers on the base and the column's top) simulated by
//! `metrocell sim` on flat ground and tilted (`--ground-tilt`), then the user's workflow:
//! `calibrate` of the declared gravity model (`mobile_manipulator_model.yaml`, every term at zero)
//! on the flat recording, `calibrate --refit poses` of the fitted model on the tilted one.
//!
//! Asserted: every concealed parameter of the cell's `terms:` within 3σ of what the flat
//! calibration recovered; the tilted ground's (roll, pitch) found by the restationing as the
//! fitted `base_tilt` within 3σ (the twin's ground tilt and the catalog's `base_tilt` are one
//! convention); on both grounds the check points' p95 in xy within 1.5× the floor the
//! instrument's noise sets, and the rigid URDF far worse. The floor: the same recording
//! restationed with the truth itself as the model (the cell file: its terms at their true
//! values, only the poses fitted — the recording's own noise, and the poses' own uncertainty),
//! checked against the analytic p95 of a 2-D Gaussian error of σ = 0.75 mm per axis,
//! σ·√(−2 ln 0.05) = 1.84 mm. And `diagnose` of the flat recording with the rigid URDF names the
//! concealed gravity terms.
//!
//! Run: `cargo build -p metrocell-cli && cargo test -p metrocell-system-tests --test twin_robot`.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use metrocell_twin::Cell;
use serde_json::Value;
use system_tests::{bin, piped, run, workspace_root};

const CELL: &str = "launch-configs/cells/mobile_manipulator.yaml";
const MODEL: &str = "launch-configs/cells/mobile_manipulator_model.yaml";
/// The tilted recording's ground: 4 mrad of roll and 12 mrad of pitch (nose up).
const TILT: (&str, [f64; 2]) = ("4mrad,-12mrad", [0.004, -0.012]);

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "metrocell_twin_robot_{name}_{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn metrocell(args: &[&OsStr]) -> Value {
    let out = run(
        piped(bin("metrocell"))
            .args(args)
            .current_dir(workspace_root()),
        Duration::from_secs(600),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "metrocell {args:?} failed:\n{stderr}");
    serde_json::from_slice(&out.stdout).unwrap_or(Value::Null)
}

/// `metrocell sim` of the cell, flat or with a ground tilt, into `dir/name`.
fn simulate(dir: &Path, name: &str, seed: u64, tilt: Option<&str>) -> PathBuf {
    let bag = dir.join(name);
    let seed = seed.to_string();
    let mut args: Vec<&OsStr> = vec![
        "sim".as_ref(),
        "--cell".as_ref(),
        CELL.as_ref(),
        "--seed".as_ref(),
        seed.as_ref(),
        "--quiet".as_ref(),
        "--clock-rate".as_ref(),
        "0".as_ref(),
        "-o".as_ref(),
        bag.as_os_str(),
    ];
    if let Some(t) = tilt {
        args.extend(["--ground-tilt".as_ref(), OsStr::new(t)]);
    }
    metrocell(&args);
    bag
}

fn calibrate(model: &Path, bag: &Path, output: &Path, refit_poses: bool) -> Value {
    let mut args: Vec<&OsStr> = vec![
        "calibrate".as_ref(),
        "--model".as_ref(),
        model.as_os_str(),
        bag.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "--json".as_ref(),
        "-".as_ref(),
    ];
    if refit_poses {
        args.extend([OsStr::new("--refit"), OsStr::new("poses")]);
    }
    metrocell(&args)
}

fn parameter(json: &Value, name: &str) -> (f64, f64) {
    let p = json["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| {
            panic!(
                "no parameter {name} in calibrate's JSON: {}",
                json["parameters"]
            )
        });
    (
        p["value"].as_f64().unwrap(),
        p["sigma"].as_f64().unwrap_or(f64::NAN),
    )
}

fn p95_xy(json: &Value, which: &str) -> f64 {
    json["check"][which]["overall"]["p95_xy_m"]
        .as_f64()
        .unwrap_or_else(|| panic!("no check.{which}.overall.p95_xy_m in {}", json["check"]))
}

/// The analytic floor: p95 of |e_xy| for e ~ N(0, σ²I₂), the Rayleigh quantile.
fn rayleigh_p95(sigma: f64) -> f64 {
    sigma * (-2.0 * 0.05f64.ln()).sqrt()
}

/// The check points on `ground`: the fitted model within 1.5× the floor (the truth restationed
/// on the same recording), the rigid URDF far off; the floor near the analytic one.
fn assert_on_target(ground: &str, fitted: &Value, truth_restationed: &Value, sigma: f64) {
    let (xy, rigid, floor) = (
        p95_xy(fitted, "fitted"),
        p95_xy(fitted, "nominal"),
        p95_xy(truth_restationed, "fitted"),
    );
    let analytic = rayleigh_p95(sigma);
    println!("{ground}: check p95 xy fitted {:.2} mm, rigid {:.2} mm; floor {:.2} mm (the truth restationed; analytic {:.2} mm), {} check points", xy * 1e3, rigid * 1e3, floor * 1e3, analytic * 1e3, fitted["check"]["fitted"]["overall"]["n"]);
    assert!(
        floor > 0.85 * analytic && floor < 1.3 * analytic,
        "{ground}: the truth's own p95 xy {floor} m is far from the noise's {analytic} m"
    );
    assert!(
        xy <= 1.5 * floor,
        "{ground}: check p95 xy {xy} m beyond 1.5× the floor {floor} m"
    );
    assert!(
        rigid > 5.0 * floor,
        "{ground}: the rigid URDF's p95 xy {rigid} m should be far off the floor {floor} m"
    );
    assert!(
        fitted["check"]["fitted"]["overall"]["n"].as_u64().unwrap() >= 300,
        "{}",
        fitted["check"]["fitted"]
    );
    assert!(
        fitted["check"]["fitted"]["unpredicted"]
            .as_array()
            .is_none_or(|u| u.is_empty()),
        "{ground}: check points left unpredicted"
    );
}

#[test]
fn the_twin_calibrated_on_flat_ground_and_restationed_on_tilted_ground_meets_the_target() {
    let dir = temp_dir("workflow");
    let root = workspace_root();
    let cell = Cell::from_path(root.join(CELL)).unwrap();
    let sigma = cell.stationing.as_ref().unwrap().point_noise;
    let flat = simulate(&dir, "flat", 1, None);
    let tilted = simulate(&dir, "tilted", 2, Some(TILT.0));
    let fitted = dir.join("fitted.yaml");
    let fit = calibrate(&root.join(MODEL), &flat, &fitted, false);
    // every concealed parameter, read from the cell's truth
    let names = cell.terms.param_specs();
    for (spec, truth) in names.iter().zip(cell.terms.params()) {
        let (v, s) = parameter(&fit, &spec.name);
        println!(
            "{} = {v:.4e} ± {s:.1e} {} (truth {truth:.4e}, {:+.1}σ)",
            spec.name,
            spec.unit,
            (v - truth) / s
        );
        assert!(
            (v - truth).abs() <= 3.0 * s,
            "{} = {v} ± {s}: the truth {truth} is beyond 3σ",
            spec.name
        );
    }
    let (roll, s_roll) = parameter(&fit, "base_tilt.roll");
    let (pitch, s_pitch) = parameter(&fit, "base_tilt.pitch");
    println!(
        "flat: base_tilt roll {:.3} ± {:.3} mrad, pitch {:.3} ± {:.3} mrad",
        roll * 1e3,
        s_roll * 1e3,
        pitch * 1e3,
        s_pitch * 1e3
    );
    assert!(
        roll.abs() <= 3.0 * s_roll && pitch.abs() <= 3.0 * s_pitch,
        "the flat floor is level: roll {roll}, pitch {pitch}"
    );
    let flat_truth = calibrate(&root.join(CELL), &flat, &dir.join("flat_truth.yaml"), true);
    assert_on_target("flat", &fit, &flat_truth, sigma);
    // the stationing step on the tilted ground: only the placements and the base's tilt move
    let restationed = calibrate(&fitted, &tilted, &dir.join("restationed.yaml"), true);
    let free: Vec<&str> = restationed["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert!(
        free.iter()
            .all(|n| n.starts_with("tracker_pose[") || n.starts_with("base_tilt.")),
        "refit poses freed {free:?}"
    );
    // the ground's tilt: the truth restationed finds it (the twin's ground tilt is the catalog's
    // base_tilt), the calibrated model the same to its physics' errors
    let tilted_truth = calibrate(
        &root.join(CELL),
        &tilted,
        &dir.join("tilted_truth.yaml"),
        true,
    );
    for (k, axis) in ["roll", "pitch"].iter().enumerate() {
        let name = format!("base_tilt.{axis}");
        let ((v, s), (t, ts)) = (
            parameter(&restationed, &name),
            parameter(&tilted_truth, &name),
        );
        println!("tilted: {name} {:.3} ± {:.3} mrad with the calibrated physics, {:.3} ± {:.3} mrad with the truth's; the ground's {:.1} mrad", v * 1e3, s * 1e3, t * 1e3, ts * 1e3, TILT.1[k] * 1e3);
        assert!(
            (t - TILT.1[k]).abs() <= 3.0 * ts && ts < 5e-4,
            "{name} = {t} ± {ts} with the truth's physics: the ground's {} beyond 3σ",
            TILT.1[k]
        );
        assert!(
            (v - t).abs() <= 3.0 * s,
            "{name} = {v} ± {s} with the calibrated physics, {t} with the truth's"
        );
    }
    assert_on_target("tilted", &restationed, &tilted_truth, sigma);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn diagnose_of_the_flat_recording_with_the_rigid_urdf_names_the_concealed_gravity_terms() {
    let dir = temp_dir("diagnose");
    let root = workspace_root();
    let flat = simulate(&dir, "flat", 3, None);
    // the declared model without its terms: the URDF alone
    let text = std::fs::read_to_string(root.join(MODEL)).unwrap();
    let rigid = text.split("\nterms:").next().unwrap().replace(
        "path: mobile_manipulator.urdf",
        &format!(
            "path: {}",
            root.join("launch-configs/cells/mobile_manipulator.urdf")
                .display()
        ),
    );
    let model = dir.join("rigid.yaml");
    std::fs::write(&model, rigid).unwrap();
    let d = metrocell(&[
        "diagnose".as_ref(),
        "--model".as_ref(),
        model.as_os_str(),
        flat.as_os_str(),
        "--json".as_ref(),
        "-".as_ref(),
    ]);
    let named: Vec<&str> = d["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["term"].as_str().unwrap_or_default())
        .collect();
    println!("diagnose named {named:?}");
    for f in d["findings"].as_array().unwrap() {
        println!("  {}", f["statement"]);
    }
    for must in ["column_bending", "tool_offset", "joint_compliance"] {
        assert!(
            named.contains(&must),
            "diagnose did not name {must}: {named:?}"
        );
    }
    let concealed = [
        "column_bending",
        "tool_offset",
        "joint_compliance",
        "joint_backlash",
    ];
    assert!(
        named.iter().all(|n| concealed.contains(n)),
        "diagnose named physics the twin does not conceal: {named:?}"
    );
    let (before, after) = (
        d["check"]["declared"]["p95_xy_m"].as_f64().unwrap(),
        d["check"]["augmented"]["p95_xy_m"].as_f64().unwrap(),
    );
    println!(
        "diagnose on the check points: p95 xy {:.2} → {:.2} mm",
        before * 1e3,
        after * 1e3
    );
    assert!(after < before / 3.0, "{}", d["check"]);
    let _ = std::fs::remove_dir_all(&dir);
}
