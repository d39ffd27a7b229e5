//! Writing a fitted model back as a cell file: the values and uncertainties read back, the
//! user's comments, units, key order and style are kept, added terms are appended, and the
//! result is still a cell the twin simulates.

mod common;

use common::cell_path;
use metrocell_physics::{ConfigValue, TermConfig};
use metrocell_twin::{write_model, Cell, CellModel, FittedParameter, ModelUpdate};
use std::collections::BTreeMap;
use std::path::Path;

fn read(text: &str) -> CellModel {
    CellModel::from_yaml_str_in(text, "written.yaml", Path::new("."))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Every fitted parameter of `model` moved by a known amount, with σ 1/20 of the move.
fn fitted(model: &CellModel) -> Vec<FittedParameter> {
    let fm = model.forward_model().unwrap();
    let specs: Vec<_> = model
        .machine_terms
        .param_specs()
        .into_iter()
        .chain(model.instrument_terms.param_specs())
        .collect();
    fm.param_names()
        .into_iter()
        .zip(fm.params())
        .zip(&specs)
        .enumerate()
        // a model without a tracker gets the pose of a recording only in its `fit` summary
        .filter(|(k, ((name, _), _))| {
            model.setup.free[*k] && (model.declares_tracker || !name.starts_with("tracker_pose"))
        })
        .map(|(k, ((name, v), spec))| {
            // a move of 1 % of the usual range, different per parameter
            // (towards the middle of the range, so the value stays possible)
            let toward = if v > 0.5 * (spec.usual.hi + spec.usual.lo) {
                -1.0
            } else {
                1.0
            };
            let step = toward * 0.01 * spec.typical_scale().min(1.0) * (1.0 + k as f64 / 10.0);
            FittedParameter {
                name,
                value: v + step,
                sigma: Some(step.abs() / 20.0),
            }
        })
        .collect()
}

fn comments(text: &str) -> Vec<&str> {
    text.lines()
        .filter_map(|l| l.find('#').map(|i| l[i..].trim_end()))
        .collect()
}

/// A cell file in block style, as a YAML emitter writes it (Python's `yaml.safe_dump(…,
/// default_flow_style=False)`, serde_yaml): every mapping and list on lines of their own, a list
/// in a mapping not indented (`translation:` then `- -1.2 m`), no comments.
fn block_style(text: &str) -> String {
    let v: serde_yaml::Value = serde_yaml::from_str(text).unwrap();
    let out = serde_yaml::to_string(&v).unwrap();
    assert!(
        !out.contains(": [") && !out.contains(": {"),
        "not block style:\n{out}"
    );
    out
}

const EXAMPLES: [&str; 7] = [
    "xfyz_shift.yaml",
    "quick_demo.yaml",
    "serial_arm_ur5.yaml",
    "delta_printer.yaml",
    "five_axis_table.yaml",
    "demo_shift.yaml",
    "demo_model.yaml",
];

#[test]
fn fitted_values_and_uncertainties_read_back_and_the_file_stays_the_users() {
    let files = EXAMPLES
        .iter()
        .flat_map(|f| {
            let text = std::fs::read_to_string(cell_path(f)).unwrap();
            [
                (format!("{f} (as written)"), text.clone()),
                (format!("{f} (block style)"), block_style(&text)),
            ]
        })
        .chain([(
            "quick_demo.yaml by yaml.safe_dump (block style)".to_string(),
            std::fs::read_to_string(format!(
                "{}/tests/data/quick_demo_safe_dump.yaml",
                env!("CARGO_MANIFEST_DIR")
            ))
            .unwrap(),
        )]);
    for (f, text) in files {
        let f = f.as_str();
        let model = read(&text);
        let params = fitted(&model);
        let fit =
            serde_yaml::from_str("{records: 120, residual_rms_um: {before: 31.2, after: 4.1}}")
                .unwrap();
        let out = write_model(
            &model,
            &ModelUpdate {
                parameters: params.clone(),
                added_terms: vec![],
                fit: Some(fit),
                ..Default::default()
            },
        )
        .unwrap();
        // the model reads back with the fitted values (within 1/100 σ) and their σ (2 digits)
        let back = read(&out);
        let fm = back.forward_model().unwrap();
        let names = fm.param_names();
        let values = fm.params();
        let u = back.uncertainty().unwrap();
        for p in &params {
            let k = names
                .iter()
                .position(|n| *n == p.name)
                .unwrap_or_else(|| panic!("{f}: {} missing", p.name));
            let sigma = p.sigma.unwrap();
            assert!(
                (values[k] - p.value).abs() <= sigma / 100.0,
                "{f}: {} = {} read back as {}",
                p.name,
                p.value,
                values[k]
            );
            assert!(
                (u[&p.name] / sigma - 1.0).abs() < 0.05,
                "{f}: σ of {} = {} read back as {}",
                p.name,
                sigma,
                u[&p.name]
            );
        }
        // every comment the user wrote is still there, in order; the keys keep their order
        let (a, b) = (comments(&text), comments(&out));
        let mut it = b.iter();
        for c in &a {
            assert!(it.any(|x| x == c), "{f}: comment lost or reordered: {c}");
        }
        let keys = |t: &str| {
            t.lines()
                .filter(|l| l.chars().next().is_some_and(|c| c.is_ascii_alphabetic()))
                .map(|l| l.split(':').next().unwrap().to_string())
                .collect::<Vec<_>>()
        };
        let mut expected = keys(&text);
        expected.extend(["uncertainty".to_string(), "fit".to_string()]);
        assert_eq!(keys(&out), expected, "{f}");
        // still a cell the twin simulates, with the fitted machine terms
        let cell = Cell::from_yaml_str(&out, f).unwrap_or_else(|e| panic!("{f}: {e}\n{out}"));
        assert_eq!(cell.terms.params(), back.machine_terms.params(), "{f}");
        // a block list keeps its style (issue 32: `translation:` came back as `- [x, y, z]`)
        if f.ends_with("(block style)") && model.declares_tracker {
            let at = out
                .find("    pose:\n")
                .and_then(|p| out[p..].find("translation:\n").map(|t| p + t))
                .unwrap_or_else(|| panic!("{f}:\n{out}"));
            let lines: Vec<&str> = out[at..].lines().skip(1).take(3).collect();
            assert!(
                lines
                    .iter()
                    .all(|l| l.trim_start().starts_with("- ") && !l.contains('[')),
                "{f}: {lines:?}"
            );
        }
        // written a second time: one uncertainty section, one fit section
        let again = write_model(
            &back,
            &ModelUpdate {
                parameters: params.clone(),
                added_terms: vec![],
                fit: Some(serde_yaml::from_str("{records: 1}").unwrap()),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(again.matches("\nuncertainty:").count(), 1, "{f}");
        assert_eq!(again.matches("\nfit:").count(), 1, "{f}");
        assert!(
            again.contains("records: 1") && !again.contains("records: 120"),
            "{f}"
        );
    }
}

#[test]
fn values_keep_the_unit_they_were_written_in() {
    let model = CellModel::from_path(cell_path("xfyz_shift.yaml")).unwrap();
    let update = ModelUpdate {
        parameters: vec![
            FittedParameter {
                name: "positioning[y].c1".into(),
                value: 5.873e-6,
                sigma: Some(0.21e-6),
            },
            FittedParameter {
                name: "thermal_scale[x].alpha".into(),
                value: 11.62e-6,
                sigma: Some(0.41e-6),
            },
            FittedParameter {
                name: "tracker_pose.tx".into(),
                value: -0.8635123,
                sigma: Some(2.1e-6),
            },
            FittedParameter {
                name: "tracker_warmup.time_constant".into(),
                value: 5312.0,
                sigma: Some(40.0),
            },
            FittedParameter {
                name: "squareness[xy].s".into(),
                value: 19.7e-6,
                sigma: None,
            },
        ],
        ..Default::default()
    };
    let out = write_model(&model, &update).unwrap();
    assert!(
        out.contains("params: {c0: 0 um, c1: 5.873 um, c2: -2 um}"),
        "{out}"
    );
    assert!(out.contains("params: {alpha: 1.1620e-5 1/K}"), "{out}");
    assert!(
        out.contains("translation: [-863.51230 mm, 194.373 mm, 677.782 mm]   # thesis P3 fixture"),
        "{out}"
    );
    assert!(out.contains("time_constant: 88.533 min}"), "{out}");
    assert!(
        out.contains("params: {s: 20 urad}"),
        "a parameter without σ (not identifiable) is left as written:\n{out}"
    );
    assert!(
        out.contains("\"positioning[y]\": {c1: 0.21 um}")
            && out.contains("\"thermal_scale[x]\": {alpha: 4.1e-7 1/K}"),
        "{out}"
    );
    assert!(!out.contains("squareness[xy]\": {"), "{out}");
}

#[test]
fn added_terms_are_appended_and_read_back() {
    let text = "# my model\nname: m\nmachine:\n  family: cartesian\n  stacking: XFYZ   # X table\n  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}\nterms:\n  - id: positioning   # first\n    options: {axis: x, order: 1}\n    params: {c0: 0 um, c1: 3 um}\n";
    let model = CellModel::from_yaml_str_in(text, "m.yaml", Path::new(".")).unwrap();
    let mut options = BTreeMap::new();
    options.insert("axis".to_string(), ConfigValue::Text("y".into()));
    let mut params = BTreeMap::new();
    params.insert("reversal".to_string(), ConfigValue::Text("0 um".into()));
    let added = TermConfig {
        id: "backlash".into(),
        options,
        params,
        use_defaults: false,
    };
    let update = ModelUpdate {
        parameters: vec![
            FittedParameter {
                name: "backlash[y].reversal".into(),
                value: 9.04e-6,
                sigma: Some(0.52e-6),
            },
            FittedParameter {
                name: "positioning[x].c1".into(),
                value: 2.5e-6,
                sigma: Some(0.1e-6),
            },
        ],
        added_terms: vec![added],
        fit: None,
        notes: vec![],
        output_dir: None,
    };
    let out = write_model(&model, &update).unwrap();
    assert!(out.contains("  - id: positioning   # first\n    options: {axis: x, order: 1}\n    params: {c0: 0 um, c1: 2.500 um}\n  - id: backlash\n    options: {axis: y}\n    params: {reversal: 9.040 um}\n"), "{out}");
    let back = read(&out);
    let fm = back.forward_model().unwrap();
    assert_eq!(
        &fm.param_names()[..3],
        [
            "positioning[x].c0",
            "positioning[x].c1",
            "backlash[y].reversal"
        ]
    );
    assert!((fm.params()[2] - 9.04e-6).abs() < 1e-12);
    assert!((back.uncertainty().unwrap()["backlash[y].reversal"] - 0.52e-6).abs() < 1e-12);
    // a model without a terms list gets one
    let bare = "name: m\nmachine: {family: cartesian, stacking: XFYZ, travel: {x: [0 m, 1 m], y: [0 m, 1 m], z: [0 m, 1 m]}}\n";
    let model = CellModel::from_yaml_str_in(bare, "m.yaml", Path::new(".")).unwrap();
    let out = write_model(
        &model,
        &ModelUpdate {
            parameters: update.parameters[..1].to_vec(),
            added_terms: update.added_terms.clone(),
            fit: None,
            ..Default::default()
        },
    )
    .unwrap();
    let back = read(&out);
    assert_eq!(
        back.forward_model().unwrap().param_names()[0],
        "backlash[y].reversal",
        "{out}"
    );
}

/// The notes the writer added as comments, unwrapped.
fn said(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("# -").or_else(|| l.strip_prefix("#  ")))
        .collect();
    lines
        .join(" ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

fn number(v: f64) -> ConfigValue {
    ConfigValue::Number(v)
}

fn term(id: &str, options: &[(&str, ConfigValue)], params: &[(&str, f64)]) -> TermConfig {
    TermConfig {
        id: id.into(),
        options: options
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect(),
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), number(*v)))
            .collect(),
        use_defaults: false,
    }
}

fn fitted_value(name: &str, value: f64, sigma: f64) -> FittedParameter {
    FittedParameter {
        name: name.into(),
        value,
        sigma: Some(sigma),
    }
}

/// `label.param` → value of a model read back.
fn values(m: &CellModel) -> BTreeMap<String, f64> {
    let fm = m.forward_model().unwrap();
    fm.param_names().into_iter().zip(fm.params()).collect()
}

/// Issue 32: `diagnose` wrote a tracker warm-up it found under `terms:`, which every command
/// then refused ("is a sensor term"). Instrument terms go where a model file keeps them.
#[test]
fn found_instrument_terms_go_where_a_model_file_keeps_them() {
    let demo_model = std::fs::read_to_string(cell_path("demo_model.yaml")).unwrap();
    for (style, text) in [
        ("as written", demo_model.clone()),
        ("block style", block_style(&demo_model)),
    ] {
        let model = read(&text);
        assert!(!model.declares_tracker);
        let update = ModelUpdate {
            parameters: vec![
                fitted_value("tracker_warmup.amplitude", 20.21e-6, 0.3e-6),
                fitted_value("tracker_warmup.time_constant", 1812.0, 96.0),
                FittedParameter {
                    name: "tracker_warmup.offset".into(),
                    value: 0.0,
                    sigma: None,
                },
                fitted_value("refraction.path_temperature_offset", 0.42, 0.05),
                fitted_value("backlash[x].reversal", 8.08e-6, 0.1e-6),
            ],
            added_terms: vec![
                term(
                    "tracker_warmup",
                    &[],
                    &[
                        ("offset", 0.0),
                        ("amplitude", 2e-5),
                        ("time_constant", 1800.0),
                    ],
                ),
                term(
                    "refraction",
                    &[],
                    &[
                        ("path_temperature_offset", 0.0),
                        ("path_pressure_offset", 0.0),
                    ],
                ),
                term(
                    "backlash",
                    &[("axis", ConfigValue::Text("x".into()))],
                    &[("reversal", 0.0)],
                ),
                // the instrument moving during the recording: the recording's, not the model's
                term(
                    "instrument_drift",
                    &[
                        ("order", number(1.0)),
                        ("rotation", ConfigValue::Bool(false)),
                        ("span", ConfigValue::List(vec![number(0.0), number(3600.0)])),
                    ],
                    &[("dx1", 0.0), ("dy1", 0.0), ("dz1", 3e-6)],
                ),
            ],
            fit: None,
            notes: vec![
                "left out: the empirical correction `empirical[z]` (no catalog term describes it)"
                    .into(),
            ],
            output_dir: None,
        };
        let out = write_model(&model, &update).unwrap();
        assert!(
            !out.contains("id: tracker_warmup")
                && !out.contains("id: refraction")
                && !out.contains("id: instrument_drift"),
            "{style}: instrument terms are not machine terms:\n{out}"
        );
        assert!(said(&out).contains("instrument_drift, found by metrocell diagnose (the instrument moved during the recording), is left out of this file"), "{style}:\n{out}");
        assert!(out.contains("id: backlash"), "{style}:\n{out}");
        let back = read(&out);
        let v = values(&back);
        assert!(
            (v["tracker_warmup.amplitude"] - 20.21e-6).abs() < 0.3e-6 / 100.0,
            "{style}: {}",
            v["tracker_warmup.amplitude"]
        );
        assert!(
            (v["tracker_warmup.time_constant"] - 1812.0).abs() < 1.0,
            "{style}"
        );
        assert!(
            (v["refraction.path_temperature_offset"] - 0.42).abs() < 0.05 / 100.0,
            "{style}"
        );
        assert!(
            (v["backlash[x].reversal"] - 8.08e-6).abs() < 1e-9,
            "{style}"
        );
        let u = back.uncertainty().unwrap();
        assert!(
            (u["tracker_warmup.amplitude"] / 0.3e-6 - 1.0).abs() < 0.05
                && (u["refraction.path_temperature_offset"] / 0.05 - 1.0).abs() < 0.05,
            "{style}: {u:?}"
        );
        // the tracker's pose is unknown: the identity start, registered from each recording
        assert!(
            back.declares_tracker && back.raw.sensors.tracker.as_ref().unwrap().pose.is_none(),
            "{style}"
        );
        let tp = back
            .forward_model()
            .unwrap()
            .instrument_param_start(metrocell_physics::TermId::TrackerPose)
            .unwrap();
        assert!(
            back.forward_model().unwrap().params()[tp..tp + 6]
                .iter()
                .all(|x| *x == 0.0)
                && back.setup.free[tp..tp + 6].iter().all(|f| *f),
            "{style}"
        );
        // what was left out, and where things went, is said in the file
        assert!(
            out.contains("# - left out: the empirical correction `empirical[z]`"),
            "{style}:\n{out}"
        );
        assert!(
            out.contains("sensors.tracker.warmup") && out.contains("sensors.tracker has no pose"),
            "{style}:\n{out}"
        );
        // the simulator needs a pose and says so
        let e = Cell::from_yaml_str(&out, "augmented.yaml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("sensors.tracker.pose") && e.contains("is required to simulate the tracker"),
            "{style}: {e}"
        );
        // written again (calibrate -o of the augmented model): nothing doubled
        let again = write_model(
            &back,
            &ModelUpdate {
                parameters: vec![fitted_value("tracker_warmup.amplitude", 20.0e-6, 0.2e-6)],
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            (values(&read(&again))["tracker_warmup.amplitude"] - 20.0e-6).abs() < 1e-9,
            "{style}:\n{again}"
        );
    }
}

/// A model with a posed tracker and a probe: a found warm-up goes into its tracker, a found
/// pretravel into its probe, and the result is still a cell the twin simulates.
#[test]
fn found_instrument_terms_join_the_sensors_a_cell_has() {
    let mut v: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(cell_path("quick_demo.yaml")).unwrap())
            .unwrap();
    v["sensors"]["tracker"]
        .as_mapping_mut()
        .unwrap()
        .remove("warmup");
    v["sensors"]["tracker"]
        .as_mapping_mut()
        .unwrap()
        .remove("station");
    v["sensors"]["probe"]
        .as_mapping_mut()
        .unwrap()
        .remove("pretravel");
    let block = serde_yaml::to_string(&v).unwrap();
    let flow = std::fs::read_to_string(cell_path("quick_demo.yaml"))
        .unwrap()
        .replace("    warmup: {offset: 0 um, amplitude: 19 um, time_constant: 30 min}   # API Tracker3 curve\n", "")
        .replace("    station: {temperature_bias: 0.3 K}\n", "")
        .replace("    pretravel:\n      options: {lobes: 3}\n      params: {mean: 10 um, lobe_cos: 3 um, lobe_sin: 0 um, vertical: 5 um}\n", "");
    for (style, text) in [("as written", flow), ("block style", block)] {
        let model = read(&text);
        assert!(
            model.instrument_terms.terms.len() == 1,
            "{style}: only the pose is declared"
        );
        let update = ModelUpdate {
            parameters: vec![
                fitted_value("tracker_warmup.amplitude", 18.7e-6, 0.2e-6),
                fitted_value("probe_pretravel.mean", 10.3e-6, 0.1e-6),
                fitted_value("refraction.path_temperature_offset", -0.31, 0.02),
            ],
            added_terms: vec![
                term(
                    "tracker_warmup",
                    &[],
                    &[
                        ("offset", 0.0),
                        ("amplitude", 1e-5),
                        ("time_constant", 1800.0),
                    ],
                ),
                term(
                    "probe_pretravel",
                    &[("lobes", number(3.0))],
                    &[
                        ("mean", 0.0),
                        ("lobe_cos", 3e-6),
                        ("lobe_sin", 0.0),
                        ("vertical", 5e-6),
                    ],
                ),
                term(
                    "refraction",
                    &[],
                    &[
                        ("path_temperature_offset", 0.0),
                        ("path_pressure_offset", 0.0),
                    ],
                ),
                term(
                    "lens_distortion",
                    &[],
                    &[
                        ("k1", 0.0),
                        ("k2", 0.0),
                        ("k3", 0.0),
                        ("p1", 0.0),
                        ("p2", 0.0),
                    ],
                ),
            ],
            ..Default::default()
        };
        let out = write_model(&model, &update).unwrap();
        let back = read(&out);
        let v = values(&back);
        assert!(
            (v["tracker_warmup.amplitude"] - 18.7e-6).abs() < 1e-9
                && (v["probe_pretravel.mean"] - 10.3e-6).abs() < 1e-9
                && (v["probe_pretravel.lobe_cos"] - 3e-6).abs() < 1e-12,
            "{style}:\n{out}"
        );
        assert!(
            (v["refraction.path_temperature_offset"] + 0.31).abs() < 1e-4,
            "{style}:\n{out}"
        );
        assert!(
            out.contains("lens_distortion") && out.contains("left out of this file"),
            "{style}: a term with no place written is said:\n{out}"
        );
        let cell = Cell::from_yaml_str(&out, "augmented.yaml")
            .unwrap_or_else(|e| panic!("{style}: {e}\n{out}"));
        let tr = cell.tracker.as_ref().unwrap();
        assert!(
            (tr.warmup.unwrap().amplitude - 18.7e-6).abs() < 1e-9
                && (tr.station.temperature_bias - 0.31).abs() < 1e-4,
            "{style}"
        );
        assert!(cell.probe.as_ref().unwrap().pretravel.is_some(), "{style}");
    }
}
