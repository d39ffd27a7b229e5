//! Tracker noise statistics at a fixed target, and recovery of the warm-up curve by fitting.

mod common;

use metrocell_twin::cell_file::CellFile;
use metrocell_twin::{Sample, SampleTruth, Simulation};

/// The demo cell reduced to one program point (the target never moves) and no machine errors.
fn fixed_target_cell() -> CellFile {
    let mut f = common::example_file("quick_demo.yaml");
    f.terms.clear();
    common::quiet_tracker(&mut f);
    f.sensors.probe = None;
    f.sensors.camera = None;
    f.program.as_mut().unwrap().grid = None;
    f.program.as_mut().unwrap().points = vec![[
        common::q("200 mm"),
        common::q("150 mm"),
        common::q("100 mm"),
    ]];
    f.program.as_mut().unwrap().dwell = common::q("100 h");
    f
}

#[test]
fn range_and_angle_residuals_match_the_spec_within_5_percent() {
    let cell = common::validate(&fixed_target_cell());
    let tr = cell.tracker.clone().unwrap();
    let sim = Simulation::new(cell, 3000.0, 11).unwrap();
    let (mut dr, mut da, mut de) = (vec![], vec![], vec![]);
    let mut rho = 0.0;
    let mut stated_var_ratio = vec![];
    for (s, t) in sim.samples_with_truth() {
        if let (Sample::Tracker(m), SampleTruth::Tracker(tt)) = (s, t) {
            rho = tt.range;
            dr.push(m.range - tt.range);
            let (_, az, el) = metrocell_twin::tracker_model::to_spherical(&tt.point);
            da.push(m.azimuth - az);
            de.push(m.elevation - el);
            // stated covariance along the line of sight = σ_ρ²
            let u = m.point / m.point.norm();
            let stated = tr.range_noise_constant + tr.range_noise_per_metre * m.range;
            stated_var_ratio.push((u.transpose() * m.covariance * u)[(0, 0)] / (stated * stated));
        }
    }
    assert_eq!(dr.len(), 30_000);
    let spec = tr.range_noise_constant + tr.range_noise_per_metre * rho;
    let (m, s) = common::mean_std(&dr);
    assert!(
        (s / spec - 1.0).abs() < 0.05,
        "range σ {s} vs spec {spec} (ρ = {rho} m)"
    );
    assert!(
        m.abs() < 4.0 * spec / (dr.len() as f64).sqrt(),
        "range mean {m}"
    );
    let (_, sa) = common::mean_std(&da);
    let (_, se) = common::mean_std(&de);
    assert!((sa / tr.angular_noise - 1.0).abs() < 0.05, "azimuth σ {sa}");
    assert!(
        (se / tr.angular_noise - 1.0).abs() < 0.05,
        "elevation σ {se}"
    );
    assert!(
        stated_var_ratio.iter().all(|r| (r - 1.0).abs() < 1e-9),
        "stated covariance inconsistent with a + bρ"
    );
}

#[test]
fn turbulence_inflates_scatter_only_inside_its_window() {
    let mut f = fixed_target_cell();
    f.sensors.tracker.as_mut().unwrap().turbulence =
        vec![metrocell_twin::cell_file::TurbulenceWindow {
            start: common::q("100 s"),
            end: common::q("200 s"),
            coefficient: common::q("20 um/m"),
        }];
    let sim = Simulation::new(common::validate(&f), 300.0, 3).unwrap();
    let (mut inside, mut outside) = (vec![], vec![]);
    for (s, t) in sim.samples_with_truth() {
        if let (Sample::Tracker(m), SampleTruth::Tracker(tt)) = (s, t) {
            let r = m.range - tt.range;
            if (100.0..200.0).contains(&m.t) {
                inside.push(r)
            } else {
                outside.push(r)
            }
        }
    }
    let (_, si) = common::mean_std(&inside);
    let (_, so) = common::mean_std(&outside);
    // at ρ ≈ 1.5 m: quiet σ ≈ 5.2 µm; inside √(5.2² + 30²) ≈ 30 µm
    assert!(si > 4.0 * so, "inside {si} outside {so}");
}

#[test]
fn warmup_curve_is_recovered_by_fitting() {
    let mut f = fixed_target_cell();
    let t = f.sensors.tracker.as_mut().unwrap();
    t.rate = Some(common::q("1 Hz"));
    t.warmup = Some(
        serde_yaml::from_str("{offset: 5 um, amplitude: 75 um, time_constant: 90 min}").unwrap(),
    );
    let sim = Simulation::new(common::validate(&f), 6.0 * 3600.0, 21).unwrap();
    // residual = measured range − true geometric range (the tracker's own error)
    let mut ts = vec![];
    let mut ys = vec![];
    for (s, tr) in sim.samples_with_truth() {
        if let (Sample::Tracker(m), SampleTruth::Tracker(tt)) = (s, tr) {
            ts.push(m.t);
            ys.push(m.range - tt.range);
        }
    }
    let sigma = common::mean_std(&ys[ys.len() - 3600..]).1; // late: drift ≈ flat, scatter ≈ noise
                                                            // Fit y = A + B(1 − e^(−t/τ)): linear in (A, B) for fixed τ; scan τ then refine.
    let fit_ab = |tau: f64| {
        let (mut s11, mut s12, mut s22, mut r1, mut r2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (t, y) in ts.iter().zip(&ys) {
            let g = 1.0 - (-t / tau).exp();
            s11 += 1.0;
            s12 += g;
            s22 += g * g;
            r1 += y;
            r2 += g * y;
        }
        let det = s11 * s22 - s12 * s12;
        let a = (s22 * r1 - s12 * r2) / det;
        let b = (s11 * r2 - s12 * r1) / det;
        let sse: f64 = ts
            .iter()
            .zip(&ys)
            .map(|(t, y)| (y - a - b * (1.0 - (-t / tau).exp())).powi(2))
            .sum();
        (a, b, sse)
    };
    let (mut lo, mut hi) = (600.0, 36_000.0);
    for _ in 0..200 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if fit_ab(m1).2 < fit_ab(m2).2 {
            hi = m2
        } else {
            lo = m1
        }
    }
    let tau = 0.5 * (lo + hi);
    let (a, b, _) = fit_ab(tau);
    // Standard errors from the Gauss–Newton normal matrix at the optimum.
    let mut n = nalgebra::Matrix3::<f64>::zeros();
    for t in &ts {
        let e = (-t / tau).exp();
        let j = nalgebra::Vector3::new(1.0, 1.0 - e, -b * t / (tau * tau) * e);
        n += j * j.transpose();
    }
    let cov = n.try_inverse().unwrap() * (sigma * sigma);
    let (ua, ub, ut) = (cov[(0, 0)].sqrt(), cov[(1, 1)].sqrt(), cov[(2, 2)].sqrt());
    println!("A = {a:.3e} ± {ua:.1e}, B = {b:.3e} ± {ub:.1e}, τ = {tau:.0} ± {ut:.0} s (σ = {sigma:.2e})");
    assert!((a - 5e-6).abs() < 3.0 * ua, "A = {a}");
    assert!((b - 75e-6).abs() < 3.0 * ub, "B = {b}");
    assert!((tau - 5400.0).abs() < 3.0 * ut, "τ = {tau}");
    assert!(
        ub < 1e-6 && ut < 200.0,
        "fit too weak to be a test: u(B) {ub}, u(τ) {ut}"
    );
}

#[test]
fn beam_breaks_drop_samples_with_a_status_flag() {
    let mut f = fixed_target_cell();
    f.sensors.tracker.as_mut().unwrap().beam_breaks =
        Some(metrocell_twin::cell_file::BeamBreakSection {
            per_hour: 60.0,
            mean_duration: common::q("2 s"),
        });
    let sim = Simulation::new(common::validate(&f), 3600.0, 8).unwrap();
    let (mut broken, mut total) = (0usize, 0usize);
    for s in sim.samples() {
        if let Sample::Tracker(m) = s {
            total += 1;
            if m.status == metrocell_twin::TrackerStatus::BeamBroken {
                broken += 1;
                assert!(m.point.x.is_nan() && m.range.is_nan() && m.covariance[(0, 0)].is_nan());
                assert!(m.refractive_index > 1.0, "air data still reported");
            } else {
                assert!(m.range.is_finite());
            }
        }
    }
    // expected fraction rate·duration = 60/3600·2 = 3.3 %; ~60 breaks → ±~20 %
    let frac = broken as f64 / total as f64;
    assert!(
        (frac / (60.0 / 3600.0 * 2.0) - 1.0).abs() < 0.4,
        "fraction broken {frac}"
    );
}

#[test]
fn thermocouples_read_truth_plus_offset_plus_stated_noise() {
    let mut f = common::example_file("xfyz_shift.yaml");
    f.sensors.tracker = None;
    f.sensors.machine_state = None;
    let cell = common::validate(&f);
    let sim = Simulation::new(cell, 3.0 * 3600.0, 5).unwrap();
    let mut by_sensor: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for (s, t) in sim.samples_with_truth() {
        if let (Sample::Temperature(m), SampleTruth::Temperature { true_value }) = (s, t) {
            assert!((m.variance - (0.02f64.powi(2) + 0.05f64.powi(2))).abs() < 1e-15);
            by_sensor
                .entry(m.sensor.to_string())
                .or_default()
                .push(m.value - true_value);
        }
    }
    assert_eq!(by_sensor.len(), 6);
    for (name, r) in &by_sensor {
        assert_eq!(r.len(), 10_800);
        let (m, s) = common::mean_std(r);
        let offset = if name == "x_right" { 0.1 } else { 0.0 };
        assert!((s / 0.02 - 1.0).abs() < 0.05, "{name}: σ {s}");
        assert!(
            (m - offset).abs() < 4.0 * 0.02 / (r.len() as f64).sqrt(),
            "{name}: mean {m}"
        );
    }
}
