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
    CellModel::from_yaml_str_in(text, "written.yaml", Path::new(".")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Every fitted parameter of `model` moved by a known amount, with σ 1/20 of the move.
fn fitted(model: &CellModel) -> Vec<FittedParameter> {
    let fm = model.forward_model().unwrap();
    let specs: Vec<_> = model.machine_terms.param_specs().into_iter().chain(model.instrument_terms.param_specs()).collect();
    fm.param_names()
        .into_iter()
        .zip(fm.params())
        .zip(&specs)
        .enumerate()
        // a model without a tracker gets the pose of a recording only in its `fit` summary
        .filter(|(k, ((name, _), _))| model.setup.free[*k] && (model.declares_tracker || !name.starts_with("tracker_pose")))
        .map(|(k, ((name, v), spec))| {
            // a move of 1 % of the usual range, different per parameter
            // (towards the middle of the range, so the value stays possible)
            let toward = if v > 0.5 * (spec.usual.hi + spec.usual.lo) { -1.0 } else { 1.0 };
            let step = toward * 0.01 * spec.typical_scale().min(1.0) * (1.0 + k as f64 / 10.0);
            FittedParameter { name, value: v + step, sigma: Some(step.abs() / 20.0) }
        })
        .collect()
}

fn comments(text: &str) -> Vec<&str> {
    text.lines().filter_map(|l| l.find('#').map(|i| l[i..].trim_end())).collect()
}

#[test]
fn fitted_values_and_uncertainties_read_back_and_the_file_stays_the_users() {
    for f in ["xfyz_shift.yaml", "quick_demo.yaml", "serial_arm_ur5.yaml", "delta_printer.yaml", "five_axis_table.yaml"] {
        let text = std::fs::read_to_string(cell_path(f)).unwrap();
        let model = CellModel::from_path(cell_path(f)).unwrap();
        let params = fitted(&model);
        let fit = serde_yaml::from_str("{records: 120, residual_rms_um: {before: 31.2, after: 4.1}}").unwrap();
        let out = write_model(&model, &ModelUpdate { parameters: params.clone(), added_terms: vec![], fit: Some(fit) }).unwrap();
        // the model reads back with the fitted values (within 1/100 σ) and their σ (2 digits)
        let back = read(&out);
        let fm = back.forward_model().unwrap();
        let names = fm.param_names();
        let values = fm.params();
        let u = back.uncertainty().unwrap();
        for p in &params {
            let k = names.iter().position(|n| *n == p.name).unwrap_or_else(|| panic!("{f}: {} missing", p.name));
            let sigma = p.sigma.unwrap();
            assert!((values[k] - p.value).abs() <= sigma / 100.0, "{f}: {} = {} read back as {}", p.name, p.value, values[k]);
            assert!((u[&p.name] / sigma - 1.0).abs() < 0.05, "{f}: σ of {} = {} read back as {}", p.name, sigma, u[&p.name]);
        }
        // every comment the user wrote is still there, in order; the keys keep their order
        let (a, b) = (comments(&text), comments(&out));
        let mut it = b.iter();
        for c in &a {
            assert!(it.any(|x| x == c), "{f}: comment lost or reordered: {c}");
        }
        let keys = |t: &str| t.lines().filter(|l| l.chars().next().is_some_and(|c| c.is_ascii_alphabetic())).map(|l| l.split(':').next().unwrap().to_string()).collect::<Vec<_>>();
        let mut expected = keys(&text);
        expected.extend(["uncertainty".to_string(), "fit".to_string()]);
        assert_eq!(keys(&out), expected, "{f}");
        // still a cell the twin simulates, with the fitted machine terms
        let cell = Cell::from_yaml_str(&out, f).unwrap_or_else(|e| panic!("{f}: {e}\n{out}"));
        assert_eq!(cell.terms.params(), back.machine_terms.params(), "{f}");
        // written a second time: one uncertainty section, one fit section
        let again = write_model(&back, &ModelUpdate { parameters: params.clone(), added_terms: vec![], fit: Some(serde_yaml::from_str("{records: 1}").unwrap()) }).unwrap();
        assert_eq!(again.matches("\nuncertainty:").count(), 1, "{f}");
        assert_eq!(again.matches("\nfit:").count(), 1, "{f}");
        assert!(again.contains("records: 1") && !again.contains("records: 120"), "{f}");
    }
}

#[test]
fn values_keep_the_unit_they_were_written_in() {
    let model = CellModel::from_path(cell_path("xfyz_shift.yaml")).unwrap();
    let update = ModelUpdate {
        parameters: vec![
            FittedParameter { name: "positioning[y].c1".into(), value: 5.873e-6, sigma: Some(0.21e-6) },
            FittedParameter { name: "thermal_scale[x].alpha".into(), value: 11.62e-6, sigma: Some(0.41e-6) },
            FittedParameter { name: "tracker_pose.tx".into(), value: -0.8635123, sigma: Some(2.1e-6) },
            FittedParameter { name: "tracker_warmup.time_constant".into(), value: 5312.0, sigma: Some(40.0) },
            FittedParameter { name: "squareness[xy].s".into(), value: 19.7e-6, sigma: None },
        ],
        ..Default::default()
    };
    let out = write_model(&model, &update).unwrap();
    assert!(out.contains("params: {c0: 0 um, c1: 5.873 um, c2: -2 um}"), "{out}");
    assert!(out.contains("params: {alpha: 1.1620e-5 1/K}"), "{out}");
    assert!(out.contains("translation: [-863.51230 mm, 194.373 mm, 677.782 mm]   # thesis P3 fixture"), "{out}");
    assert!(out.contains("time_constant: 88.533 min}"), "{out}");
    assert!(out.contains("params: {s: 20 urad}"), "a parameter without σ (not identifiable) is left as written:\n{out}");
    assert!(out.contains("\"positioning[y]\": {c1: 0.21 um}") && out.contains("\"thermal_scale[x]\": {alpha: 4.1e-7 1/K}"), "{out}");
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
    let added = TermConfig { id: "backlash".into(), options, params, use_defaults: false };
    let update = ModelUpdate {
        parameters: vec![FittedParameter { name: "backlash[y].reversal".into(), value: 9.04e-6, sigma: Some(0.52e-6) }, FittedParameter { name: "positioning[x].c1".into(), value: 2.5e-6, sigma: Some(0.1e-6) }],
        added_terms: vec![added],
        fit: None,
    };
    let out = write_model(&model, &update).unwrap();
    assert!(out.contains("  - id: positioning   # first\n    options: {axis: x, order: 1}\n    params: {c0: 0 um, c1: 2.500 um}\n  - id: backlash\n    options: {axis: y}\n    params: {reversal: 9.040 um}\n"), "{out}");
    let back = read(&out);
    let fm = back.forward_model().unwrap();
    assert_eq!(&fm.param_names()[..3], ["positioning[x].c0", "positioning[x].c1", "backlash[y].reversal"]);
    assert!((fm.params()[2] - 9.04e-6).abs() < 1e-12);
    assert!((back.uncertainty().unwrap()["backlash[y].reversal"] - 0.52e-6).abs() < 1e-12);
    // a model without a terms list gets one
    let bare = "name: m\nmachine: {family: cartesian, stacking: XFYZ, travel: {x: [0 m, 1 m], y: [0 m, 1 m], z: [0 m, 1 m]}}\n";
    let model = CellModel::from_yaml_str_in(bare, "m.yaml", Path::new(".")).unwrap();
    let out = write_model(&model, &ModelUpdate { parameters: update.parameters[..1].to_vec(), added_terms: update.added_terms.clone(), fit: None }).unwrap();
    let back = read(&out);
    assert_eq!(back.forward_model().unwrap().param_names()[0], "backlash[y].reversal", "{out}");
}
