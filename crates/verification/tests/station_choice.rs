//! The tracker station a plan suggests, and whether the uncertainty it states for the
//! identified error map is honest: over simulated verifications from that station (the
//! tracker's noise drawn, the pose identified with the errors), the fitted map's errors
//! against the truth fall within the stated σ at the stated rate.

use metrocell_estimation::simulated_records::{records, TrackerNoise};
use metrocell_estimation::volumetric_monte_carlo::error_map;
use metrocell_estimation::{fit, FitOptions};
use metrocell_physics::Signals;
use metrocell_twin::CellModel;
use metrocell_verification::tracker_station::{
    assess, candidate_ring, facing, planned, ranked, Blocked, SightLimits,
};
use metrocell_verification::Mesh;
use nalgebra::Vector3;
use std::path::Path;

const NOISE: TrackerNoise = TrackerNoise {
    constant: 4e-6,
    per_metre: 0.8e-6,
    angular: 3e-6,
};

fn limits() -> SightLimits {
    SightLimits {
        min_range: 0.5,
        max_range: 15.0,
        acceptance: 30f64.to_radians(),
        reflector_facing: None,
    }
}

/// P3's identification: positioning and straightness of X and Y (order 3) and XY squareness,
/// the tracker's pose identified with them.
fn model() -> CellModel {
    let mut terms = String::new();
    for a in ["x", "y"] {
        terms += &format!("  - {{id: positioning, options: {{axis: {a}, order: 3, travel: [0 mm, 400 mm]}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| **d != a) {
            terms += &format!("  - {{id: straightness, options: {{axis: {a}, direction: {d}, order: 3, travel: [0 mm, 400 mm]}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        }
    }
    terms += "  - {id: squareness, options: {pair: xy}, params: {s: 0 urad}}\n";
    let text = format!("name: plan\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {{x: [0 mm, 400 mm], y: [0 mm, 400 mm], z: [0 mm, 400 mm]}}\nsensors:\n  tracker:\n    pose: {{translation: [-863.527 mm, 194.373 mm, 677.782 mm], euler_xyz: [0 deg, 0 deg, 0 deg]}}\nterms:\n{terms}");
    CellModel::from_yaml_str_in(&text, "plan.yaml", Path::new(".")).unwrap()
}

fn mesh() -> Vec<[f64; 3]> {
    Mesh {
        min: [0.0, 0.0, 0.0],
        max: [0.4, 0.4, 0.0],
        step: 0.1,
    }
    .points()
    .unwrap()
}

#[test]
fn farther_stations_state_larger_uncertainty_and_too_near_ones_are_refused() {
    let m = model();
    let fm = m.forward_model().unwrap();
    let at = fm.params();
    let pts = mesh();
    let centre = Vector3::new(0.2, 0.2, 0.0);
    let ring = candidate_ring(centre, &[1.0, 2.0, 4.0], &[0.5], 1);
    let sd: Vec<f64> = ring
        .iter()
        .map(|s| {
            let a = assess(&fm, &m.setup, &at, &pts, &[], s, &limits(), NOISE).unwrap();
            assert!(a.sees_all(), "{:?}", a.blocked);
            a.max_sd
        })
        .collect();
    println!(
        "largest σ of the error map from 1, 2, 4 m: {:.2} / {:.2} / {:.2} µm",
        sd[0] * 1e6,
        sd[1] * 1e6,
        sd[2] * 1e6
    );
    assert!(sd[0] < sd[1] && sd[1] < sd[2], "{sd:?}");
    // 0.3 m above the centre: the middle points are closer than 0.5 m
    let near = facing(
        centre + Vector3::new(0.0, 0.0, 0.3),
        centre + Vector3::new(1.0, 0.0, 0.0),
    );
    let a = assess(&fm, &m.setup, &at, &pts, &[], &near, &limits(), NOISE).unwrap();
    assert!(!a.sees_all());
    assert!(
        a.blocked
            .iter()
            .any(|b| matches!(b, Blocked::TooClose { .. })),
        "{:?}",
        a.blocked
    );
    assert!(a.max_sd.is_nan(), "not evaluated when blind");
    // a reflector facing away from a station sees nothing of it
    let away = SightLimits {
        reflector_facing: Some(Vector3::new(-1.0, 0.0, 0.0)),
        ..limits()
    };
    let a = assess(&fm, &m.setup, &at, &pts, &[], &ring[0], &away, NOISE).unwrap();
    assert_eq!(a.blocked.len(), pts.len());
    assert!(matches!(a.blocked[0], Blocked::OffReflector { .. }));
}

#[test]
fn the_stated_map_uncertainty_covers_simulated_verifications_at_its_rate() {
    let m = model();
    let fm = m.forward_model().unwrap();
    let names = fm.param_names();
    let mut truth = fm.params();
    for (n, v) in [
        ("positioning[x].c1", 40e-6),
        ("positioning[x].c2", -15e-6),
        ("positioning[y].c1", 25e-6),
        ("straightness[x:y].c2", 12e-6),
        ("straightness[y:x].c3", -8e-6),
        ("squareness[xy].s", 100e-6),
    ] {
        truth[names.iter().position(|k| k == n).unwrap()] = v;
    }
    let pts = mesh();
    let centre = Vector3::new(0.2, 0.2, 0.0);
    let candidates = candidate_ring(centre, &[1.0, 2.0], &[0.0, 0.6], 8);
    let assessed: Vec<_> = candidates
        .iter()
        .map(|s| assess(&fm, &m.setup, &truth, &pts, &[], s, &limits(), NOISE).unwrap())
        .collect();
    let order = ranked(&assessed);
    let best = &assessed[order[0]];
    let fewest = assessed
        .iter()
        .filter(|a| a.sees_all())
        .map(|a| a.held.len())
        .min()
        .unwrap();
    assert_eq!(best.held.len(), fewest);
    println!(
        "best of {} stations: {:?}, largest σ {:.2} µm, mean {:.2} µm",
        assessed.len(),
        best.station,
        best.max_sd * 1e6,
        best.mean_sd * 1e6
    );
    // the truth with the tracker at the chosen station
    let i = names.iter().position(|k| k == "tracker_pose.tx").unwrap();
    let mut placed = truth.clone();
    placed[i..i + 3].copy_from_slice(best.station.position.as_slice());
    placed[i + 3] = 0.0;
    placed[i + 4] = 0.0;
    placed[i + 5] = best.station.yaw;
    let q: Vec<Vec<f64>> = pts.iter().map(|p| p.to_vec()).collect();
    let true_map = error_map(&fm, &placed, &q, &Signals::default()).unwrap();
    let plan = planned(&pts, &[]);
    let mut z = vec![];
    for trial in 0..60u64 {
        let data = records(&fm, &placed, &plan, NOISE, Some(7000 + trial));
        let f = fit(&fm, &m.setup, &data, None, &FitOptions::default()).unwrap();
        let fitted = error_map(&fm, &f.x, &q, &Signals::default()).unwrap();
        for k in 0..pts.len() {
            for c in 0..3 {
                let sd = best.sd[k][c];
                if sd > 1e-9 {
                    z.push((fitted[k][c] - true_map[k][c]) / sd);
                }
            }
        }
    }
    let within = |k: f64| z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64;
    println!(
        "{} components: within 1σ {:.3}, 2σ {:.3}, 3σ {:.3}",
        z.len(),
        within(1.0),
        within(2.0),
        within(3.0)
    );
    assert!((0.60..0.76).contains(&within(1.0)), "{}", within(1.0));
    assert!(within(2.0) > 0.92, "{}", within(2.0));
    assert!(within(3.0) > 0.985, "{}", within(3.0));
}
