//! Issue 27 on recordings no metrocell code made: the mobile manipulator of
//! `bags/independent/robot/` (numpy, from mechanics and from how a total station and an
//! accelerometer work) — a telescoping column and a 6R arm that bend under gravity, a prism read
//! by a levelled total station from three setups, groups of fit and check points.
//!
//! The user's workflow: `bag import` of each ground's export; `calibrate` of the model with the
//! gravity terms declared on the flat floor (one pose per setup, the base's tilt, the
//! compensator's prior); `calibrate --refit poses` of the fitted model on the seesaw (15 mrad of
//! pitch) — the stationing step. Asserted: the check points' p95 (xy and z) within 1.5× what
//! the instrument's noise alone gives (the answer key's target) on both grounds; the prism
//! offset, the shoulder's compliance and the column foot's within 3σ of the truth; a setup with
//! too few fit points named and its check points reported unpredicted; `diagnose` of the rigid
//! model names the column's bending and the prism offset, and scores itself on the check points;
//! without the base accelerometer's readings the gravity terms are listed as not tried, with why.
//! Run: `METROCELL_PYTHON=.venv/bin/python cargo test -p metrocell-system-tests --test robot_suite`
//! (needs `cargo build -p metrocell-cli`).

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde_json::Value;
use system_tests::{bin, piped, python, run, workspace_root};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell_robot_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The one-seed sample of the robot suite (flat floor and seesaw), its answer key.
fn sample(dir: &Path) -> (PathBuf, Value) {
    let suite = dir.join("suite");
    let args: [&OsStr; 8] = [
        "bags/independent/robot/generate_robot_suite.py".as_ref(),
        "--out".as_ref(),
        suite.as_os_str(),
        "--seeds".as_ref(),
        "1".as_ref(),
        "--sample".as_ref(),
        "--no-reference-calibration".as_ref(),
        "--floor-reps".as_ref(),
    ];
    let out = run(
        piped(python())
            .args(args)
            .arg("10")
            .current_dir(workspace_root()),
        Duration::from_secs(300),
    );
    assert!(
        out.status.success(),
        "generate_robot_suite.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let answers: Value =
        serde_json::from_str(&std::fs::read_to_string(suite.join("answers.json")).unwrap())
            .unwrap();
    (suite.join("seed_1"), answers["seeds"]["1"].clone())
}

fn metrocell(args: &[&OsStr]) -> (Value, String) {
    let out = run(piped(bin("metrocell")).args(args), Duration::from_secs(600));
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.success(),
        "metrocell {:?} failed:\n{stderr}",
        args
    );
    let json = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (json, stderr)
}

fn import(seed: &Path, ground: &str, csv: Option<&Path>) -> PathBuf {
    import_with(seed, ground, csv, &seed.join(ground).join("mapping.yaml"))
}

fn import_with(seed: &Path, ground: &str, csv: Option<&Path>, mapping: &Path) -> PathBuf {
    let bag = seed.join(format!(
        "bag_{ground}_{}_{}",
        if csv.is_some() {
            "edited"
        } else {
            "as_exported"
        },
        mapping.file_stem().unwrap().to_string_lossy()
    ));
    let csv = csv
        .map(Path::to_path_buf)
        .unwrap_or_else(|| seed.join(ground).join("export.csv"));
    metrocell(&[
        "bag".as_ref(),
        "import".as_ref(),
        csv.as_os_str(),
        "--mapping".as_ref(),
        mapping.as_os_str(),
        "-o".as_ref(),
        bag.as_os_str(),
    ]);
    bag
}

fn calibrate(model: &Path, bag: &Path, output: &Path, refit_poses: bool) -> (Value, String) {
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

/// The fitted check points within the answer key's targets (1.5× the noise floor).
fn assert_on_target(json: &Value, truth: &Value, ground: &str) {
    let c = &truth["conditions"][ground];
    let fitted = &json["check"]["fitted"]["overall"];
    let (xy, z) = (
        fitted["p95_xy_m"].as_f64().unwrap(),
        fitted["p95_z_m"].as_f64().unwrap(),
    );
    let (txy, tz) = (
        c["target_p95_xy_m"].as_f64().unwrap(),
        c["target_p95_z_m"].as_f64().unwrap(),
    );
    let rigid = json["check"]["nominal"]["overall"]["p95_xy_m"]
        .as_f64()
        .unwrap();
    println!(
        "{ground}: check p95 xy {:.2} mm (rigid {:.2} mm), z {:.2} mm; targets {:.2} / {:.2} mm",
        xy * 1e3,
        rigid * 1e3,
        z * 1e3,
        txy * 1e3,
        tz * 1e3
    );
    assert!(
        xy <= txy && z <= tz,
        "{ground}: check p95 xy {xy} m, z {z} m beyond the targets {txy} / {tz} m"
    );
    assert!(rigid > 3.0 * txy, "{ground}: the rigid model's p95 xy {rigid} m should be far off (the recording hides gravity physics)");
    assert!(
        fitted["n"].as_u64().unwrap() > 100,
        "{ground}: too few check points predicted: {fitted}"
    );
    assert!(
        json["check"]["fitted"]["unpredicted"]
            .as_array()
            .unwrap()
            .is_empty(),
        "{ground}: check points left unpredicted"
    );
}

fn parameter(json: &Value, name: &str) -> (f64, f64) {
    let p = json["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("no parameter {name} in calibrate's JSON"));
    (p["value"].as_f64().unwrap(), p["sigma"].as_f64().unwrap())
}

fn within_3_sigma(json: &Value, name: &str, truth: f64) {
    let (v, s) = parameter(json, name);
    println!(
        "{name} = {v:.4e} ± {s:.1e} (truth {truth:.4e}, {:.1}σ)",
        (v - truth) / s
    );
    assert!(
        (v - truth).abs() <= 3.0 * s,
        "{name} = {v} ± {s}, the truth {truth} is beyond 3σ"
    );
}

#[test]
fn calibrated_on_the_flat_floor_and_restationed_on_the_seesaw_the_check_points_meet_the_target() {
    let dir = temp_dir("workflow");
    let (seed, truth) = sample(&dir);
    let flat = import(&seed, "flat_floor", None);
    let seesaw = import(&seed, "seesaw_forward", None);
    let fitted = dir.join("fitted.yaml");
    let (fit, _) = calibrate(&seed.join("model_gravity.yaml"), &flat, &fitted, false);
    assert_on_target(&fit, &truth, "flat_floor");
    let robot = &truth["robot"];
    for (k, axis) in ["dx", "dy", "dz"].iter().enumerate() {
        within_3_sigma(
            &fit,
            &format!("tool_offset.{axis}"),
            robot["prism_offset_error_m"][k].as_f64().unwrap(),
        );
    }
    within_3_sigma(
        &fit,
        "joint_compliance.k_shoulder_lift",
        robot["joint_compliance_rad_per_Nm"]["shoulder_lift"]
            .as_f64()
            .unwrap(),
    );
    within_3_sigma(
        &fit,
        "column_bending[column_lower].foot",
        robot["column"]["foot_compliance_rad_per_Nm"]
            .as_f64()
            .unwrap(),
    );
    base_accelerometer_alignment_matches_its_truth(&fit, robot, "flat_floor");
    // the placements are per recording: not written into the fitted model
    let text = std::fs::read_to_string(&fitted).unwrap();
    assert!(
        !text.contains("tracker_pose[") && !text.contains("base_tilt"),
        "the fitted model holds per-recording poses:\n{text}"
    );
    let (restationed, _) = calibrate(&fitted, &seesaw, &dir.join("restationed.yaml"), true);
    assert_on_target(&restationed, &truth, "seesaw_forward");
    // only the placements moved; the seesaw's pitch is found by the levelled instrument
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
    let (pitch, sigma) = parameter(&restationed, "base_tilt.pitch");
    let tilt = truth["conditions"]["seesaw_forward"]["tilt_rad"].clone();
    println!("seesaw: base_tilt.pitch {pitch:.5} ± {sigma:.5} rad; the ground's tilt {tilt}");
    assert!(
        pitch.abs() > 0.010 && pitch.abs() < 0.025,
        "the seesaw's 15 mrad pitch not found: {pitch}"
    );
    // (on the seesaw the estimate is printed in calibrate's words; its pitch came 2.8σ off the
    // truth on this seed — the instrument's tilt there absorbs ~0.5 mrad of model error — so it
    // is not asserted)
    let _ = std::fs::remove_dir_all(&dir);
}

/// The base accelerometer's alignment (its reading's tilt minus the levelled instrument's)
/// against the generator's truth: the sensor reads Mᵀ·f + b (M its mounting misalignment, a
/// rotation vector r; b its bias; bags/independent/robot/accelerometer.py), so to first order its
/// "up" is off by (−r_y + b_x/g, r_x + b_y/g): δroll = r_x + b_y/g, δpitch = r_y − b_x/g.
fn base_accelerometer_alignment_matches_its_truth(json: &Value, robot: &Value, ground: &str) {
    let a = &json["accelerometer_alignment"];
    let base = &robot["accelerometers"]["base"];
    let (r, b) = (&base["misalignment_rotvec_rad"], &base["bias_m_per_s2"]);
    let g = 9.80665;
    let f = |v: &Value, i: usize| v[i].as_f64().unwrap();
    let expected = [f(r, 0) + f(b, 1) / g, f(r, 1) - f(b, 0) / g];
    for (k, name) in ["roll", "pitch"].iter().enumerate() {
        let (v, s) = (
            a[format!("{name}_rad")].as_f64().unwrap(),
            a[format!("sigma_{name}_rad")].as_f64().unwrap(),
        );
        println!("{ground}: accelerometer_alignment[base].{name} {:+.3} ± {:.3} mrad (truth {:+.3} mrad)", v * 1e3, s * 1e3, expected[k] * 1e3);
        // 3σ plus the second-order terms of the first-order truth (~δ², µrad)
        assert!(
            (v - expected[k]).abs() <= 3.0 * s + 2e-5,
            "{ground}: {name} {v} ± {s} rad, truth {}: {a}",
            expected[k]
        );
    }
    assert_eq!(a["sensor"], "base");
    assert!(a["prediction_effect_max_m"].as_f64().unwrap() < 1e-3, "{a}");
}

#[test]
fn a_setup_with_too_few_fit_points_is_named_and_its_check_points_unpredicted() {
    let dir = temp_dir("short_setup");
    let (seed, _) = sample(&dir);
    // keep one fit point of setup S2
    let text = std::fs::read_to_string(seed.join("flat_floor").join("export.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let cols: Vec<&str> = header.split(',').collect();
    let (setup, role) = (
        cols.iter().position(|c| *c == "Setup").unwrap(),
        cols.iter().position(|c| *c == "Role").unwrap(),
    );
    let mut kept_one = false;
    let mut out = vec![header.to_string()];
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        if f[setup] == "S2" && f[role] == "fit" {
            if kept_one {
                continue;
            }
            kept_one = true;
        }
        out.push(l.to_string());
    }
    let csv = dir.join("edited.csv");
    std::fs::write(&csv, out.join("\n") + "\n").unwrap();
    let bag = import(&seed, "flat_floor", Some(&csv));
    let (json, stderr) = calibrate(
        &seed.join("model.yaml"),
        &bag,
        &dir.join("fitted.yaml"),
        false,
    );
    assert!(
        stderr.contains("setup `S2` has 1 fit point(s), fewer than the 2 its pose needs"),
        "{stderr}"
    );
    let unpredicted = json["check"]["fitted"]["unpredicted"].as_array().unwrap();
    assert!(
        !unpredicted.is_empty() && unpredicted.iter().all(|u| u["setup"] == "S2"),
        "{unpredicted:?}"
    );
    assert!(json["check"]["fitted"]["setups"].get("S2").is_none());
    assert!(
        json["check"]["fitted"]["setups"]["S1"]["n"]
            .as_u64()
            .unwrap()
            > 0
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn diagnose_names_the_column_and_the_prism_offset_on_the_rigid_model() {
    let dir = temp_dir("diagnose");
    let (seed, _) = sample(&dir);
    let flat = import(&seed, "flat_floor", None);
    let (d, _) = metrocell(&[
        "diagnose".as_ref(),
        "--model".as_ref(),
        seed.join("model.yaml").as_os_str(),
        flat.as_os_str(),
        "--json".as_ref(),
        "-".as_ref(),
    ]);
    let named: Vec<String> = d["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["term"].as_str().unwrap_or_default().to_string())
        .collect();
    println!("diagnose named {named:?}");
    for must in ["column_bending", "tool_offset"] {
        assert!(
            named.iter().any(|n| n == must),
            "diagnose did not name {must}: {named:?}"
        );
    }
    let allowed = [
        "column_bending",
        "tool_offset",
        "joint_compliance",
        "joint_backlash",
        "link_thermal_expansion",
    ];
    assert!(
        named.iter().all(|n| allowed.contains(&n.as_str())),
        "diagnose named physics the truth does not have: {named:?}"
    );
    // it scores itself on the check points it kept out
    let (before, after) = (
        d["check"]["declared"]["p95_xy_m"].as_f64().unwrap(),
        d["check"]["augmented"]["p95_xy_m"].as_f64().unwrap(),
    );
    println!(
        "diagnose on the check points: p95 xy {:.2} → {:.2} mm",
        before * 1e3,
        after * 1e3
    );
    assert!(
        after < before / 3.0 && d["check"]["augmented"]["n"].as_u64().unwrap() > 100,
        "{}",
        d["check"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn without_the_base_accelerometer_the_gravity_terms_are_not_tried_and_say_why() {
    let dir = temp_dir("no_accelerometer");
    let (seed, _) = sample(&dir);
    // the export's base accelerometer columns ignored by the mapping
    let text = std::fs::read_to_string(seed.join("flat_floor").join("mapping.yaml")).unwrap();
    let mut mapping: Vec<String> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("accel.base."))
        .map(str::to_string)
        .collect();
    let ignore = mapping
        .iter()
        .position(|l| l.starts_with("ignore:"))
        .unwrap();
    mapping[ignore] = mapping[ignore].replace(
        "[\"Group\"",
        "[\"acc_base_x [m/s2]\", \"acc_base_y [m/s2]\", \"acc_base_z [m/s2]\", \"Group\"",
    );
    let path = dir.join("no_base_accelerometer.yaml");
    std::fs::write(&path, mapping.join("\n") + "\n").unwrap();
    let bag = import_with(&seed, "flat_floor", None, &path);
    let (d, _) = metrocell(&[
        "diagnose".as_ref(),
        "--model".as_ref(),
        seed.join("model.yaml").as_os_str(),
        bag.as_os_str(),
        "--json".as_ref(),
        "-".as_ref(),
    ]);
    let not_tried = d["not_tried"].as_array().unwrap();
    for term in ["joint_compliance", "joint_backlash", "column_bending"] {
        let entry = not_tried
            .iter()
            .find(|n| n["term"] == term)
            .unwrap_or_else(|| panic!("{term} not in not_tried: {not_tried:?}"));
        let reason = entry["reason"].as_str().unwrap();
        assert!(
            reason.contains("base accelerometer `base`") && reason.contains("accel.base.x|y|z"),
            "{reason}"
        );
    }
    let named: Vec<&str> = d["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["term"].as_str().unwrap())
        .collect();
    assert!(
        !named.contains(&"joint_compliance") && !named.contains(&"column_bending"),
        "{named:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stated σ of the robot's physics cover the truth at their stated rate: ten independent
/// robots (seeds 3–12, each its own truth and recording), calibrated on the flat floor; the
/// fraction of judged parameters (compliance and backlash per joint, the prism offset per axis)
/// within 2σ and 3σ of the truth must have a 95 % binomial interval holding 95.4 % and 99.7 %
/// (`coverage_robot_parameters.py`, which also prints each family).
#[test]
fn the_stated_uncertainties_cover_the_truth_at_their_stated_rate_over_ten_robots() {
    let dir = temp_dir("coverage");
    let suite = dir.join("suite");
    let mut gen = piped(python());
    gen.arg("bags/independent/robot/generate_robot_suite.py")
        .arg("--out")
        .arg(&suite)
        .args(["--no-reference-calibration", "--floor-reps", "2", "--seeds"]);
    gen.args((3..=12).map(|s| s.to_string()))
        .current_dir(workspace_root());
    let out = run(&mut gen, Duration::from_secs(600));
    assert!(
        out.status.success(),
        "generate_robot_suite.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = dir.join("coverage.json");
    let mut cov = piped(python());
    cov.arg("bags/independent/robot/coverage_robot_parameters.py")
        .arg("--metrocell")
        .arg(bin("metrocell"))
        .arg("--suite")
        .arg(&suite)
        .arg("--out")
        .arg(&json);
    let out = run(cov.current_dir(workspace_root()), Duration::from_secs(600));
    println!("{}", String::from_utf8_lossy(&out.stdout));
    let c: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let all = &c["coverage"]["all"];
    assert!(
        all["1"]["n"].as_u64().unwrap() >= 120,
        "too few judged parameters: {all}"
    );
    for (k, rate) in [("2", 0.9545), ("3", 0.9973)] {
        let lo = all[k]["interval95"][0].as_f64().unwrap();
        let hi = all[k]["interval95"][1].as_f64().unwrap();
        assert!(lo <= rate && rate <= hi, "the fraction within {k}σ, interval [{lo:.3}, {hi:.3}], excludes the stated {rate}: {all}");
    }
    assert!(
        out.status.success() && c["stated_rates_covered"] == true,
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
