//! Data metrocell did not make: tracker-style exports written by numpy (bags/independent/
//! make_exports.py — its own column names, mm, U95, random points in random order, irregular
//! rounds, its own noise, points already in the machine frame), read here column by column into
//! records (the CLI reads them through `bag import`; tests/system does that path) and diagnosed
//! with bags/independent/model.yaml. Needs METROCELL_PYTHON (a Python with numpy).

mod common;

use std::collections::BTreeMap;

use metrocell_diagnose::DiagnoseOptions;
use metrocell_estimation::{MeasurementRecord, RecordFrame, RecordKind, RecordSet};
use metrocell_physics::Signals;
use nalgebra::{Matrix3, Vector3};

fn python() -> String {
    std::env::var("METROCELL_PYTHON").expect("METROCELL_PYTHON must name a Python with numpy (e.g. /work/main/.venv/bin/python): this test runs the independent generator")
}

fn bags() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bags/independent")
}

/// Records of one export: the CSV's own columns, converted as bags/independent/mapping.yaml says.
fn records(csv: &str) -> RecordSet {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("{name} not in {header:?}"))
    };
    let (t, xn, yn, zn, x, y, z, u95, bed, air, dx, dy, dz, id) = (
        col("Time [s]"),
        col("Xnom [mm]"),
        col("Ynom [mm]"),
        col("Znom [mm]"),
        col("X [mm]"),
        col("Y [mm]"),
        col("Z [mm]"),
        col("U95 [mm]"),
        col("T_bed [C]"),
        col("T_air [C]"),
        col("Dir X"),
        col("Dir Y"),
        col("Dir Z"),
        col("PointID"),
    );
    let mut out = Vec::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let v = |k: usize| f[k].parse::<f64>().unwrap();
        let nominal = Vector3::new(v(xn), v(yn), v(zn)) * 1e-3;
        let sigma = v(u95) * 1e-3 / 2.0;
        let mut s = Signals {
            axis_position: [Some(nominal.x), Some(nominal.y), Some(nominal.z)],
            ..Signals::default()
        };
        s.approach_direction = [Some(v(dx)), Some(v(dy)), Some(v(dz))];
        s.temperatures = BTreeMap::from([("bed".to_string(), v(bed)), ("air".to_string(), v(air))]);
        out.push(MeasurementRecord {
            time: 1_741_073_400.0 + v(t),
            point_id: f[id].to_string(),
            channel: "numpy_export".into(),
            kind: RecordKind::Point,
            q: nominal.iter().copied().collect(),
            measured: Vector3::new(v(x), v(y), v(z)) * 1e-3,
            covariance: Matrix3::identity() * sigma * sigma,
            signals: s,
        });
    }
    RecordSet {
        check: Vec::new(),
        frame: RecordFrame::Machine,
        records: out,
        rejected: vec![],
        sources: vec![],
    }
}

#[test]
fn numpy_exports_are_diagnosed() {
    let dir = std::env::temp_dir().join(format!("metrocell_numpy_exports_{}", std::process::id()));
    let status = std::process::Command::new(python())
        .arg(bags().join("make_exports.py"))
        .arg("--out")
        .arg(&dir)
        .arg("--seed")
        .arg("3")
        .status()
        .expect("run the generator");
    assert!(status.success());
    let model = std::fs::read_to_string(bags().join("model.yaml")).unwrap();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    for variant in ["scale", "reversal", "null", "null_t"] {
        let data = records(&std::fs::read_to_string(dir.join(format!("{variant}.csv"))).unwrap());
        let d = common::run(&model, &data, &DiagnoseOptions::default());
        eprintln!("--- {variant}");
        common::show(&d);
        let t = &truth[variant];
        match t["label"].as_str() {
            Some(label) => {
                assert!(!d.report.findings.is_empty(), "{variant}: nothing found");
                let f = &d.report.findings[0];
                assert_eq!(f.label, label, "{variant}");
                assert_eq!(
                    d.report.findings.len(),
                    1,
                    "{variant}: also claimed {:?}",
                    d.report
                        .findings
                        .iter()
                        .map(|f| &f.label)
                        .collect::<Vec<_>>()
                );
                for (name, value) in t["parameters"].as_object().unwrap() {
                    let p = &f.parameters[name];
                    let want = value.as_f64().unwrap();
                    assert!(
                        (p.value - want).abs() < 3.0 * p.sigma.unwrap(),
                        "{variant}: {name} = {} ± {:?}, truth {want}",
                        p.value,
                        p.sigma
                    );
                }
                assert!(
                    d.report.after.heldout_rms_m < 1.2 * d.report.noise_rms_m,
                    "{variant}: after {:e} vs floor {:e}",
                    d.report.after.heldout_rms_m,
                    d.report.noise_rms_m
                );
            }
            None => {
                assert!(
                    d.report.findings.is_empty(),
                    "{variant}: claimed {:?}",
                    d.report
                        .findings
                        .iter()
                        .map(|f| &f.label)
                        .collect::<Vec<_>>()
                );
                assert!(
                    d.report.unexplained.is_empty(),
                    "{variant}: {:?}",
                    d.report
                        .unexplained
                        .iter()
                        .map(|u| &u.statement)
                        .collect::<Vec<_>>()
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Stated uncertainties off by a factor of two either way (an export whose U95 was taken for σ,
/// or σ for U95): the selection does not rely on them (its tests use the residual variance), so
/// the same term is named and null data stay quiet; the noise verdict says which level it used.
#[test]
fn stated_uncertainties_off_by_a_factor_change_no_verdict() {
    let dir = std::env::temp_dir().join(format!("metrocell_numpy_factor_{}", std::process::id()));
    let status = std::process::Command::new(python())
        .arg(bags().join("make_exports.py"))
        .arg("--out")
        .arg(&dir)
        .arg("--seed")
        .arg("5")
        .arg("--variants")
        .arg("scale")
        .arg("null")
        .status()
        .expect("run the generator");
    assert!(status.success());
    let model = std::fs::read_to_string(bags().join("model.yaml")).unwrap();
    for factor in [2.0, 0.5] {
        for variant in ["scale", "null"] {
            let mut data =
                records(&std::fs::read_to_string(dir.join(format!("{variant}.csv"))).unwrap());
            data.records
                .iter_mut()
                .for_each(|r| r.covariance *= factor * factor);
            let d = common::run(&model, &data, &DiagnoseOptions::default());
            eprintln!("--- {variant}, stated σ × {factor}");
            common::show(&d);
            let labels: Vec<&str> = d.report.findings.iter().map(|f| f.label.as_str()).collect();
            match variant {
                "scale" => assert_eq!(labels, vec!["thermal_scale[x]"], "σ × {factor}"),
                _ => assert!(
                    labels.is_empty() && d.report.unexplained.is_empty(),
                    "σ × {factor}: {labels:?}"
                ),
            }
            assert_eq!(
                d.report.noise.basis, "residual_scatter",
                "σ × {factor}: {}",
                d.report.noise.statement
            );
            assert!(
                (d.report.noise.scale * factor - 1.0).abs() < 0.15,
                "σ × {factor}: scale {}",
                d.report.noise.scale
            );
            assert!(d.report.explained, "σ × {factor}: {:?}", d.report.remaining);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
