//! Seed 001 (thesis, P3): Monte Carlo of the volumetric verification of an XFYZ machine with a
//! laser tracker — the volumetric error map with its uncertainty, and the shape of the thesis's
//! result: tens of µm of volumetric error before, a residual near 12.34 ± 7.06 µm after.
//!
//! Set-up as P3 states it: workspace 0–400 mm in X and Y at Z = 0; the tracker at
//! (−863.527, 194.373, 677.782) mm, Euler XYZ (0.0339°, 0.0343°, 59.4652°), its pose known
//! to the fit; noise normal with 24 µrad on the angles and 4 µm + 0.8 µm/m on the range (read
//! as σ). The trials also move the tracker (±50 mm, ±2° in yaw around P3's place, known to the
//! fit, as each placement would be registered). What differs from P3, and why: its true error
//! functions ("approximation functions obtained in previous verification") are not in the
//! thesis, so the truth here is a planar error model of our own at the magnitudes its initial
//! error implies (77 ± 41 µm); its 1000 trials are 200 here (test time); its identification
//! minimises Ev over its own parameterisation, here the catalog's series.

mod common;

use common::{index, records, Planned, TrackerNoise};
use metrocell_estimation::map_gauge::MapGauge;
use metrocell_estimation::volumetric_monte_carlo::{mean_sd, volumetric_monte_carlo};
use metrocell_estimation::FitOptions;
use metrocell_physics::Signals;
use metrocell_twin::CellModel;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

const P3_NOISE: TrackerNoise = TrackerNoise {
    constant: 4e-6,
    per_metre: 0.8e-6,
    angular: 24e-6,
};
const TRIALS: usize = 200;

fn model() -> CellModel {
    let mut terms = String::new();
    for a in ["x", "y"] {
        terms += &format!("  - {{id: positioning, options: {{axis: {a}, order: 3, travel: [0 mm, 400 mm]}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| **d != a) {
            terms += &format!("  - {{id: straightness, options: {{axis: {a}, direction: {d}, order: 3, travel: [0 mm, 400 mm]}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        }
    }
    terms += "  - {id: squareness, options: {pair: xy}, params: {s: 0 urad}}\n";
    let text = format!("name: p3\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {{x: [0 mm, 400 mm], y: [0 mm, 400 mm], z: [0 mm, 400 mm]}}\nsensors:\n  tracker:\n    pose: {{translation: [-863.527 mm, 194.373 mm, 677.782 mm], euler_xyz: [0.0339 deg, 0.0343 deg, 59.4652 deg]}}\nestimation:\n  tracker_pose: {{free: []}}\nterms:\n{terms}");
    CellModel::from_yaml_str_in(&text, "p3.yaml", Path::new(".")).unwrap()
}

#[test]
fn thesis_monte_carlo_shape_and_an_honest_map() {
    let m = model();
    let fm = m.forward_model().unwrap();
    let start = fm.params();
    let mut truth = start.clone();
    let set = |t: &mut Vec<f64>, n: &str, v: f64| t[index(&fm, n)] = v;
    for (n, v) in [
        ("positioning[x].c0", 30e-6),
        ("positioning[x].c1", 45e-6),
        ("positioning[x].c2", -20e-6),
        ("positioning[x].c3", 8e-6),
        ("positioning[y].c0", -20e-6),
        ("positioning[y].c1", 35e-6),
        ("positioning[y].c2", 15e-6),
        ("positioning[y].c3", -6e-6),
        ("straightness[x:y].c2", 12e-6),
        ("straightness[x:z].c1", -25e-6),
        ("straightness[x:z].c2", 10e-6),
        ("straightness[y:x].c2", -10e-6),
        ("straightness[y:z].c1", 20e-6),
        ("straightness[y:z].c3", 5e-6),
        ("squareness[xy].s", 120e-6),
    ] {
        // (× 1.6: the magnitude of P3's initial error)
        set(&mut truth, n, 1.6 * v);
    }
    // verification points: a 9 × 9 grid over 400 × 400 mm at Z = 0
    let mut plan = vec![];
    for i in 0..9 {
        for j in 0..9 {
            plan.push(Planned {
                q: vec![0.05 * i as f64, 0.05 * j as f64, 0.0],
                approach: [1.0; 3],
                temperatures: vec![],
                time_on: 3.0 * 3600.0,
                tool_offset_shift: None,
            });
        }
    }
    let points: Vec<Vec<f64>> = plan.iter().map(|p| p.q.clone()).collect();
    let pose = index(&fm, "tracker_pose.tx");
    let mc = volumetric_monte_carlo(
        &fm,
        &m.setup,
        &truth,
        &points,
        &Signals::default(),
        // the fits start at the placed tracker: the map's rigid part is the truth's, as P3 had it
        MapGauge::AsFitted,
        TRIALS,
        |k| {
            // this trial's placement, known to the fit
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + k as u64);
            let mut placed = truth.clone();
            for c in 0..3 {
                placed[pose + c] += rng.random_range(-0.05..0.05);
            }
            placed[pose + 5] += rng.random_range(-2.0f64..2.0).to_radians();
            let data = records(&fm, &placed, &plan, P3_NOISE, Some(k as u64));
            let mut s = start.clone();
            s[pose..pose + 6].copy_from_slice(&placed[pose..pose + 6]);
            (data, Some(s))
        },
        &FitOptions::default(),
    )
    .unwrap();
    assert_eq!(mc.failed, 0);
    let (init_mean, init_sd) = mean_sd(&mc.initial_moduli);
    let (res_mean, res_sd) = mean_sd(&mc.residual_moduli);
    println!("initial volumetric error {:.2} ± {:.2} µm (thesis 77.39 ± 40.91); residual after {:.2} ± {:.2} µm (thesis 12.34 ± 7.06) over {} trials × {} points", init_mean * 1e6, init_sd * 1e6, res_mean * 1e6, res_sd * 1e6, TRIALS, points.len());
    // the shape: about 12 ± 7 µm after (the "before" figure is the chosen truth's error, scaled
    // to the thesis's size by construction, so it is printed, not asserted)
    assert!(
        (6e-6..20e-6).contains(&res_mean) && (3e-6..12e-6).contains(&res_sd),
        "residual {res_mean:e} ± {res_sd:e}"
    );
    assert!(res_mean < init_mean / 3.0);
    // the map's uncertainty is honest: the fitted map is unbiased (mean within 4 standard errors
    // of the truth) and its spread over the trials matches the fit's own linearised σ
    let mut ratios = vec![];
    for i in 0..points.len() {
        for c in 0..3 {
            let (mu, sd, lin, t) = (
                mc.mean_fitted[i][c],
                mc.sd_fitted[i][c],
                mc.linearised_sd[i][c],
                mc.true_errors[i][c],
            );
            assert!(
                (mu - t).abs() < 4.0 * sd / (TRIALS as f64).sqrt() + 1e-9,
                "point {i} axis {c}: mean {mu:e} vs truth {t:e} (sd {sd:e})"
            );
            if lin > 1e-7 {
                ratios.push(sd / lin);
            }
        }
    }
    let (r_mean, _) = mean_sd(&ratios);
    println!(
        "Monte Carlo σ / linearised σ over the map: mean {r_mean:.3} over {} components",
        ratios.len()
    );
    assert!(
        (0.85..1.15).contains(&r_mean),
        "Monte Carlo spread vs the fit's σ: {r_mean:.3}"
    );
}
