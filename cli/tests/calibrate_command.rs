//! `metrocell calibrate` end to end on a `metrocell sim` recording of the quick demo cell
//! (issue 15): the cell conceals α = 10.2e-6 1/K on the X scale; the model starts from the
//! handbook 11.5e-6 the thermal node is configured with. The fit must land on 10.2e-6 within its
//! stated uncertainty — and far outside it from 11.5e-6 — because it fitted α, not because it
//! was told. The fitted model reads back (sim, calibrate), the report and the JSON are written.

mod common;

use common::metrocell;

fn dir(name: &str) -> std::path::PathBuf {
    common::scratch("calibrate", name)
}

fn cell(name: &str) -> String {
    format!(
        "{}/../launch-configs/cells/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// The quick demo as the user's model: the same machine and terms, every value at a start a
/// user would have (α the handbook 11.5e-6, the others 0), the tracker where it was set up.
fn quick_demo_model() -> String {
    let text = std::fs::read_to_string(cell("quick_demo.yaml")).unwrap();
    let out = text
        .replace("params: {alpha: 10.2e-6 1/K}   # the real scale: not the handbook 11.5e-6 the thermal node is configured with", "params: {alpha: 11.5e-6 1/K}   # the handbook value for steel")
        .replace("params: {a1: 3 um, b1: -2 um}", "params: {a1: 0 um, b1: 0 um}")
        .replace("params: {reversal: 8 um}", "params: {reversal: 0 um}")
        .replace("warmup: {offset: 0 um, amplitude: 19 um, time_constant: 30 min}", "warmup: {offset: 0 um, amplitude: 10 um, time_constant: 20 min}");
    assert_ne!(out, text);
    assert!(out.contains("alpha: 11.5e-6") && !out.contains("10.2e-6"));
    out
}

#[test]
fn quick_demo_alpha_is_fitted_not_configured() {
    let d = dir("quick_demo");
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            &cell("quick_demo.yaml"),
            "--duration",
            "40min",
            "--no-camera-frames",
            "--quiet",
            "-o",
            "bag",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    std::fs::write(d.join("model.yaml"), quick_demo_model()).unwrap();
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "model.yaml",
            "bag",
            "-o",
            "fitted.yaml",
            "--report",
            "report",
            "--json",
            "result.json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    println!("{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("result.json")).unwrap()).unwrap();
    let param = |name: &str| {
        json["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap_or_else(|| panic!("{name} not fitted: {json:#}"))
            .clone()
    };
    let alpha = param("thermal_scale[x].alpha");
    let (a, u) = (
        alpha["value"].as_f64().unwrap(),
        alpha["sigma"].as_f64().expect("α is identifiable"),
    );
    assert!(
        ((a - 10.2e-6) / u).abs() < 3.0,
        "α = {a:e} ± {u:e}: not within 3σ of the concealed 10.2e-6"
    );
    assert!(
        ((a - 11.5e-6) / u).abs() > 4.0,
        "α = {a:e} ± {u:e} does not tell the real scale from the handbook 11.5e-6"
    );
    assert!(
        u < 0.3e-6,
        "σ(α) = {u:e}: too loose to close the 1.3e-6 gap"
    );
    let reversal = param("backlash[x].reversal");
    assert!(
        ((reversal["value"].as_f64().unwrap() - 8e-6) / reversal["sigma"].as_f64().unwrap()).abs()
            < 4.0,
        "{reversal}"
    );
    // what remains is the tracker's noise (χ²/dof near 1), nothing was left out
    let chi2 = json["chi2_per_dof"].as_f64().unwrap();
    assert!((0.8..1.25).contains(&chi2), "χ²/dof {chi2}");
    assert!(
        out.contains("thermal_scale[x].alpha = ")
            && out.contains("µm/m/K")
            && out.contains("Residual RMS per coordinate"),
        "{out}"
    );
    // the fitted model: α in place in the user's unit, its σ in `uncertainty:`, readable by sim and calibrate
    let fitted = std::fs::read_to_string(d.join("fitted.yaml")).unwrap();
    assert!(
        fitted.contains("# the handbook value for steel")
            && fitted.contains("\"thermal_scale[x]\": {alpha: "),
        "{fitted}"
    );
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            "fitted.yaml",
            "--duration",
            "10s",
            "--no-camera-frames",
            "--quiet",
            "-o",
            "bag_from_fitted",
        ],
        &d,
    );
    assert_eq!(code, 0, "the fitted model simulates: {out}{err}");
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "fitted.yaml",
            "bag",
            "-o",
            "refitted.yaml",
        ],
        &d,
    );
    assert_eq!(code, 0, "the fitted model calibrates again: {out}{err}");
    let html = std::fs::read_to_string(d.join("report/index.html")).unwrap();
    for needle in [
        "Residuals",
        "Error functions",
        "Identifiability",
        "Uncertainty budget",
        "thermal_scale[x].alpha",
    ] {
        assert!(html.contains(needle), "report lacks {needle}");
    }
    for f in [
        "residual_histogram",
        "residual_time",
        "residual_workspace",
        "error_x",
        "error_y",
        "error_z",
    ] {
        assert!(
            d.join(format!("report/figures/{f}.svg")).exists(),
            "figure {f}"
        );
    }
}

#[test]
fn bad_input_is_named() {
    let d = dir("bad");
    std::fs::write(d.join("model.yaml"), quick_demo_model()).unwrap();
    let (code, _, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "model.yaml",
            "no_such_bag",
            "-o",
            "f.yaml",
        ],
        &d,
    );
    assert_eq!(code, 2);
    assert!(err.contains("no_such_bag"), "{err}");
    let (code, _, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "missing.yaml",
            "no_such_bag",
            "-o",
            "f.yaml",
        ],
        &d,
    );
    assert_eq!(code, 2);
    assert!(err.contains("missing.yaml"), "{err}");
    let (code, _, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "model.yaml",
            "bag",
            "-o",
            "f.yaml",
            "--loss",
            "square",
        ],
        &d,
    );
    assert_eq!(code, 2);
    assert!(err.contains("huber, cauchy, linear"), "{err}");
}

/// A touch probe's pretravel is fitted from its hits: the suite's probing cell (bags/cases/
/// case_09: eight directions in XY and one down at 24 points) with the model's pretravel at 0.
#[test]
fn probe_pretravel_is_fitted_from_the_probe_hits() {
    let d = dir("probe_pretravel");
    // the suite keeps 1 Hz joint states (only what a point needs); a probe's vertical hit comes
    // as the machine leaves the point, so here they are recorded at 20 Hz
    let text = std::fs::read_to_string(format!(
        "{}/../bags/cases/case_09/truth.yaml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace(
        "machine_state: {rate: 1 Hz}",
        "machine_state: {rate: 20 Hz}",
    );
    std::fs::write(d.join("truth.yaml"), &text).unwrap();
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            "truth.yaml",
            "--duration",
            "20min",
            "--no-camera-frames",
            "--quiet",
            "-o",
            "bag",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    let model = text.replace(
        "params: {mean: 4 um, lobe_cos: 2 um, lobe_sin: -1.5 um, vertical: 3 um}",
        "params: {mean: 0 um, lobe_cos: 0 um, lobe_sin: 0 um, vertical: 0 um}",
    );
    assert_ne!(model, text);
    std::fs::write(d.join("model.yaml"), model).unwrap();
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "model.yaml",
            "bag",
            "-o",
            "fitted.yaml",
            "--json",
            "result.json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    println!("{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("result.json")).unwrap()).unwrap();
    for (name, truth) in [
        ("mean", 4e-6),
        ("lobe_cos", 2e-6),
        ("lobe_sin", -1.5e-6),
        ("vertical", 3e-6),
    ] {
        let p = json["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == format!("probe_pretravel.{name}"))
            .unwrap_or_else(|| panic!("probe_pretravel.{name} not fitted: {json:#}"));
        let (v, s) = (
            p["value"].as_f64().unwrap(),
            p["sigma"].as_f64().expect("identifiable"),
        );
        assert!(
            ((v - truth) / s).abs() < 3.0,
            "{name} = {v:e} ± {s:e}, truth {truth:e}"
        );
    }
    let chi2 = json["chi2_per_dof"].as_f64().unwrap();
    assert!((0.8..1.25).contains(&chi2), "χ²/dof {chi2}");
    // without the hits there is nothing to fit: the model has no other measurement
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "model.yaml",
            "bag",
            "-o",
            "none.yaml",
            "--no-probe-hits",
        ],
        &d,
    );
    assert_ne!(code, 0, "{out}{err}");
    assert!(err.contains("no measurements"), "{err}");
}

/// Issue 32 item 2: a model in block style (Python's `yaml.safe_dump(…, default_flow_style=False)`
/// of quick_demo.yaml) came back from `calibrate -o` with its tracker translation as
/// `translation:` / `- [-1.2 m, 0.2 m, 0.6 m]`, a list in a list every reader refused. The fitted
/// values go where the items stand, and the output reads back in calibrate and sim.
#[test]
fn a_block_style_model_keeps_its_style() {
    let d = dir("block_style");
    let block = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../crates/twin/tests/data/quick_demo_safe_dump.yaml"),
    )
    .unwrap();
    std::fs::write(d.join("model.yaml"), &block).unwrap();
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            "model.yaml",
            "--duration",
            "3min",
            "--no-camera-frames",
            "-o",
            "bag",
            "--quiet",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            "model.yaml",
            "bag",
            "-o",
            "fitted.yaml",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    let fitted = std::fs::read_to_string(d.join("fitted.yaml")).unwrap();
    let at = fitted
        .find("\n  tracker:\n")
        .and_then(|t| fitted[t..].find("      translation:\n").map(|k| t + k))
        .unwrap_or_else(|| panic!("{fitted}"));
    let items: Vec<&str> = fitted[at..].lines().skip(1).take(3).collect();
    assert!(
        items
            .iter()
            .all(|l| l.starts_with("      - ") && l.ends_with(" m") && !l.contains('[')),
        "{items:?}"
    );
    assert!(
        fitted
            .lines()
            .filter(|l| l.trim_start().starts_with("- ["))
            .count()
            == 0,
        "no list in a list:\n{fitted}"
    );
    for args in [
        vec![
            "calibrate",
            "--model",
            "fitted.yaml",
            "bag",
            "-o",
            "again.yaml",
        ],
        vec![
            "sim",
            "--cell",
            "fitted.yaml",
            "--duration",
            "1min",
            "--no-camera-frames",
            "-o",
            "again_bag",
            "--quiet",
        ],
    ] {
        let (code, out, err) = metrocell(&args, &d);
        assert_eq!(code, 0, "{args:?}: {out}{err}");
    }
}
