//! The test-only `disturbances:` section (crates/twin/src/disturbance.rs): with the same seed,
//! a cell with a drift cycling in time and a local workspace bump gives readings that differ
//! from the same cell without them by exactly δ(t, q) — in the truth's displacement, in the
//! tracker's point (turned into the tracker frame), in the probe's recorded point (−δ: the axes
//! read P − d) — and by nothing else; the shared model, which knows no disturbance, still
//! predicts the undisturbed cell's readings.

mod common;

use metrocell_twin::cell_file::CellFile;
use metrocell_twin::{Sample, SampleTruth, Simulation};
use nalgebra::Vector3;

const DISTURBANCES: &str = "
time_cycles: [{amplitude: [3 um, -2 um, 12 um], period: 40 s, phase: 30 deg}]
workspace_bumps: [{amplitude: [0 um, 15 um, 4 um], centre: [40 mm, 20 mm, 10 mm], width: 30 mm}]
";

fn pair(name: &str) -> (CellFile, CellFile) {
    let plain = common::example_file(name);
    let mut disturbed = plain.clone();
    disturbed.disturbances = Some(serde_yaml::from_str(DISTURBANCES).unwrap());
    (plain, disturbed)
}

/// δ computed here from the section's equations (independently of the module).
fn delta(t: f64, q: Vector3<f64>) -> Vector3<f64> {
    let cycle = Vector3::new(3e-6, -2e-6, 12e-6)
        * (std::f64::consts::TAU * t / 40.0 + 30f64.to_radians()).sin();
    let r2 = (q - Vector3::new(0.04, 0.02, 0.01)).norm_squared();
    cycle + Vector3::new(0.0, 15e-6, 4e-6) * (-r2 / (2.0 * 0.03 * 0.03)).exp()
}

#[test]
fn tracker_readings_move_by_delta_and_nothing_else() {
    let (plain, disturbed) = pair("xfyz_shift.yaml");
    let (a, b) = (
        Simulation::new(common::validate(&plain), 90.0, 5).unwrap(),
        Simulation::new(common::validate(&disturbed), 90.0, 5).unwrap(),
    );
    let rotation = a.cell().tracker.as_ref().unwrap().pose.rotation;
    let (mut n, mut largest) = (0, 0.0f64);
    for ((sa, ta), (sb, tb)) in a.samples_with_truth().zip(b.samples_with_truth()) {
        match (sa, ta, sb, tb) {
            (
                Sample::Tracker(ra),
                SampleTruth::Tracker(ta),
                Sample::Tracker(rb),
                SampleTruth::Tracker(tb),
            ) => {
                let d = delta(ra.t, ta.commanded);
                assert!(
                    (tb.displacement - ta.displacement - d).norm() < 1e-15,
                    "t = {}: truth moved by {:?}, δ = {d:?}",
                    ra.t,
                    tb.displacement - ta.displacement
                );
                if ra.range.is_finite() {
                    // same seed, same noise draws: the reading moves by δ seen from the tracker, up
                    // to the noise's second-order dependence on the point (the angular noise turns
                    // δ by ~3 µrad, σ_ρ grows 0.8 µm/m with the range): ~1e-10 m against δ ~ 1e-5 m
                    let moved = rb.point - ra.point;
                    assert!(
                        (moved - rotation.transpose() * d).norm() < 1e-9,
                        "t = {}: reading moved by {moved:?}, expected {:?}, truth moved {:?}",
                        ra.t,
                        rotation.transpose() * d,
                        tb.tool_point - ta.tool_point
                    );
                    largest = largest.max(d.norm());
                    n += 1;
                }
            }
            (Sample::Temperature(x), _, Sample::Temperature(y), _) => {
                assert_eq!(x.value, y.value, "temperatures are untouched")
            }
            (x, _, y, _) => assert_eq!(
                std::mem::discriminant(&x),
                std::mem::discriminant(&y),
                "the streams stay in step"
            ),
        }
    }
    assert!(
        n > 500 && largest > 10e-6,
        "{n} readings, largest δ {largest:e} m: the test saw the disturbance"
    );
}

#[test]
fn probe_hits_read_minus_delta() {
    let (plain, disturbed) = pair("quick_demo.yaml");
    let (a, b) = (
        Simulation::new(common::validate(&plain), 120.0, 3).unwrap(),
        Simulation::new(common::validate(&disturbed), 120.0, 3).unwrap(),
    );
    let hits = |s: &Simulation| {
        s.samples()
            .filter_map(|x| {
                if let Sample::ProbeHit(h) = x {
                    Some(h)
                } else {
                    None
                }
            })
            .collect::<Vec<_>>()
    };
    let (ha, hb) = (hits(&a), hits(&b));
    assert!(!ha.is_empty() && ha.len() == hb.len());
    let tool_offset = a.cell().machine.tool_offset;
    for (x, y) in ha.iter().zip(&hb) {
        let q = x.nominal - tool_offset;
        assert!(
            (y.recorded - x.recorded + delta(x.t, q)).norm() < 1e-15,
            "hit at t = {}",
            x.t
        );
    }
}

#[test]
fn jointed_families_reject_the_section() {
    let (_, disturbed) = {
        let plain = common::example_file("serial_arm_ur5.yaml");
        let mut d = plain.clone();
        d.disturbances = Some(serde_yaml::from_str(DISTURBANCES).unwrap());
        (plain, d)
    };
    let e = metrocell_twin::Cell::from_file(&disturbed)
        .unwrap_err()
        .to_string();
    common::assert_mentions(&e, &["disturbances", "cartesian and delta"]);
}
