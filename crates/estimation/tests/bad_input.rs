//! Bad input to a batch fit: NaN measurements, gross outliers (a beam break that slipped
//! through), a singular design, a recording without the signal a term needs — a clear message,
//! a robust fit that ignores outliers and says how many and which, never a panic.

mod common;

use common::{index, records, Planned, THESIS_TRACKER};
use metrocell_estimation::{fit, FitError, FitOptions};
use metrocell_solver::Loss;
use metrocell_twin::CellModel;
use nalgebra::Vector3;
use std::path::Path;

const MODEL: &str = "name: m\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}\n  tool_offset: [0 mm, 0 mm, -150 mm]\nsensors:\n  tracker:\n    pose: {translation: [-0.9 m, 0.2 m, 0.7 m], euler_xyz: [0 deg, 0 deg, 60 deg]}\nterms:\n  - {id: positioning, options: {axis: x, order: 2, travel: [0 mm, 800 mm]}, params: {c0: 0 um, c1: 0 um, c2: 0 um}}\n  - {id: squareness, options: {pair: xy}, params: {s: 0 urad}}\n  - {id: backlash, options: {axis: y}, params: {reversal: 0 um}}\n  - {id: thermal_scale, options: {axis: x, sensors: [{name: x_left, position: 0 m}, {name: x_right, position: 0.8 m}]}, params: {alpha: 11.5e-6 1/K}}\n";

fn plan() -> Vec<Planned> {
    let mut v = vec![];
    for i in 0..5 {
        for j in 0..4 {
            for k in 0..3 {
                for (n, dir) in [1.0, -1.0].into_iter().enumerate() {
                    let t = 20.5 + 2.0 * ((i * 24 + j * 6 + k * 2 + n) % 7) as f64 / 6.0;
                    v.push(Planned {
                        q: vec![0.2 * i as f64, 0.5 * j as f64 / 3.0, 0.2 * k as f64],
                        approach: [dir; 3],
                        temperatures: vec![("x_left".into(), t), ("x_right".into(), t + 0.3)],
                        time_on: 3600.0,
                        tool_offset_shift: None,
                    });
                }
            }
        }
    }
    v
}

fn setup() -> (CellModel, Vec<f64>) {
    let m = CellModel::from_yaml_str_in(MODEL, "m.yaml", Path::new(".")).unwrap();
    let fm = m.forward_model().unwrap();
    let mut truth = fm.params();
    for (n, v) in [
        ("positioning[x].c1", 12e-6),
        ("positioning[x].c2", -5e-6),
        ("squareness[xy].s", 20e-6),
        ("backlash[y].reversal", 9e-6),
        ("thermal_scale[x].alpha", 10.2e-6),
    ] {
        truth[index(&fm, n)] = v;
    }
    (m, truth)
}

#[test]
fn nan_measurements_are_skipped_and_named() {
    let (m, truth) = setup();
    let fm = m.forward_model().unwrap();
    let mut data = records(&fm, &truth, &plan(), THESIS_TRACKER, Some(1));
    data.records[3].measured.x = f64::NAN;
    data.records[17].q[1] = f64::INFINITY;
    let f = fit(&fm, &m.setup, &data, None, &FitOptions::default()).unwrap();
    assert_eq!(
        f.skipped
            .iter()
            .map(|s| (s.index, s.point_id.as_str()))
            .collect::<Vec<_>>(),
        [(3, "p3"), (17, "p17")]
    );
    assert!(f.skipped[0].reason.contains("not finite") && f.skipped[1].reason.contains("joints"));
    assert_eq!(f.used.len(), data.len() - 2);
    let k = index(&fm, "backlash[y].reversal");
    assert!(((f.x[k] - 9e-6) / f.parameters[k].sigma.unwrap()).abs() < 4.0);
}

#[test]
fn outliers_are_down_weighted_counted_and_named() {
    let (m, truth) = setup();
    let fm = m.forward_model().unwrap();
    let mut data = records(&fm, &truth, &plan(), THESIS_TRACKER, Some(2));
    for (i, off) in [(5usize, 400e-6), (40, -250e-6), (77, 600e-6)] {
        data.records[i].measured += Vector3::new(off, 0.3 * off, 0.0);
    }
    let robust = fit(&fm, &m.setup, &data, None, &FitOptions::default()).unwrap();
    let plain = fit(
        &fm,
        &m.setup,
        &data,
        None,
        &FitOptions {
            loss: Loss::Linear,
            ..FitOptions::default()
        },
    )
    .unwrap();
    assert_eq!(
        robust.outliers.iter().map(|o| o.index).collect::<Vec<_>>(),
        [5, 40, 77],
        "{:?}",
        robust.outliers
    );
    assert!(
        robust.downweighted >= 3 && robust.downweighted <= 9,
        "{}",
        robust.downweighted
    );
    // the robust fit stays with the truth; the plain one is pulled off it
    let k = index(&fm, "positioning[x].c1");
    let z = |f: &metrocell_estimation::Fit| (f.x[k] - 12e-6) / f.parameters[k].sigma.unwrap();
    assert!(z(&robust).abs() < 3.0, "robust z {}", z(&robust));
    let worst_plain = (0..truth.len())
        .filter(|&j| plain.parameters[j].free && plain.parameters[j].sigma.is_some())
        .map(|j| ((plain.x[j] - robust.x[j]) / robust.parameters[j].sigma.unwrap()).abs())
        .fold(0.0, f64::max);
    assert!(
        worst_plain > 3.0,
        "three 250–600 µm outliers must move a plain fit by more than 3σ (moved {worst_plain:.1}σ)"
    );
}

#[test]
fn a_singular_design_is_named_not_a_panic() {
    let (m, truth) = setup();
    let fm = m.forward_model().unwrap();
    // every measurement at one X position, one approach direction: nothing along X is seen
    let plan: Vec<Planned> = plan()
        .into_iter()
        .filter(|p| p.q[0] == 0.4 && p.approach[0] > 0.0)
        .collect();
    let data = records(&fm, &truth, &plan, THESIS_TRACKER, Some(3));
    let f = fit(&fm, &m.setup, &data, None, &FitOptions::default()).unwrap();
    let held: Vec<&str> = f.held.iter().map(|h| h.name.as_str()).collect();
    for name in [
        "positioning[x].c1",
        "positioning[x].c2",
        "backlash[y].reversal",
    ] {
        assert!(
            held.contains(&name),
            "{name} must be named as not identifiable: {held:?}"
        );
    }
    assert!(f.held.iter().all(|h| h.combination.contains(&h.name)));
    // too few points for the free parameters: the number to measure is said
    let few = records(&fm, &truth, &plan[..2], THESIS_TRACKER, Some(3));
    let e = fit(&fm, &m.setup, &few, None, &FitOptions::default()).unwrap_err();
    assert!(
        matches!(e, FitError::TooFew { .. }) && e.to_string().contains("measure at least"),
        "{e}"
    );
}

#[test]
fn a_missing_signal_names_the_term_the_signal_and_the_record() {
    let (m, truth) = setup();
    let fm = m.forward_model().unwrap();
    let mut data = records(&fm, &truth, &plan(), THESIS_TRACKER, Some(4));
    for r in &mut data.records[10..] {
        r.signals.temperatures.remove("x_right");
    }
    let e = fit(&fm, &m.setup, &data, None, &FitOptions::default())
        .unwrap_err()
        .to_string();
    for needle in [
        "record 10",
        "p10",
        "thermal_scale[x]",
        "x_right",
        "/temperature/",
    ] {
        assert!(e.contains(needle), "`{needle}` missing from: {e}");
    }
}
