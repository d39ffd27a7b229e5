//! Column growth with lag on twin data (thesis Ch. 5.5.3 column-growth result): the twin's
//! `xfyz_shift` cell grows its column by 4 µm/K along −Z, lagging the column sensor by 20 min,
//! over an 8-hour shift. A fixed point (program point 0) is measured by the tracker every
//! 30 min. After correction by the `thermal_growth` term the Z drift of that point stays within
//! ±5 µm:
//!   * with the known coefficient and lag, over the whole shift;
//!   * with g and τ fitted online from the point's measurements in hours 0–4, on the held-out
//!     hours 4–8 (and the fit recovers g and τ within 3 of its standard uncertainties).
//!
//! The Z drift of one dwell is the mean of its ~30 tracker readings (single readings scatter by
//! ~4 µm, the tracker's stated noise). The cell's tracker warm-up is switched off (it drifts the
//! range by 75 µm and is the tracker node's correction, not this one); no other term of the
//! cell acts along Z, so the point's static Z error is zero.

use metrocell_compensation::{GrowthCompensator, GrowthFit, GrowthSpec, ThermalCompensator, ThermalScaleCompensator};
use metrocell_twin::{Cell, Sample, SampleTruth, Simulation, TrackerStatus};
use nalgebra::{Matrix2, Matrix3, Vector3};

const HOUR: f64 = 3600.0;
const G_TRUE: f64 = 4e-6;
const TAU_TRUE: f64 = 1200.0;

fn cell() -> Cell {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../twin/examples/cells/xfyz_shift.yaml");
    let text = std::fs::read_to_string(path).unwrap();
    let warm = "warmup: {offset: 0 um, amplitude: 75 um, time_constant: 90 min}";
    let state = "machine_state: {rate: 100 Hz}";
    assert!(text.contains(warm) && text.contains(state), "xfyz_shift.yaml changed; update this test");
    let text = text.replace(warm, "warmup: {offset: 0 um, amplitude: 0 um, time_constant: 90 min}").replace(state, "machine_state: {rate: 1 Hz}");
    Cell::from_yaml_str(&text, path).unwrap()
}

fn growth(coefficient: f64, time_constant: f64) -> GrowthCompensator {
    GrowthCompensator::new(GrowthSpec {
        sensor: "column".into(),
        direction: Vector3::new(0.0, 0.0, -1.0),
        coefficient,
        coefficient_uncertainty: 0.0,
        time_constant: Some(time_constant),
        time_constant_uncertainty: 0.0,
        reference_temperature: 20.0,
        calibration_uncertainty: 0.05,
    })
    .unwrap()
}

/// One tracker reading of the reference point: time, measured − nominal (workpiece frame), its
/// covariance, and the Z drift predicted at that instant (by the known-parameter compensator; for the held-out hours by the fitted one, less the fitted offset).
struct Reading {
    t: f64,
    error: Vector3<f64>,
    cov: Matrix3<f64>,
    predicted_z: f64,
}

/// Mean per dwell (readings closer than 60 s belong to one dwell): (time, mean of f).
fn dwell_means(readings: &[Reading], f: impl Fn(&Reading) -> f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64, usize)> = Vec::new();
    let mut last_t = f64::NEG_INFINITY;
    for r in readings {
        if r.t - last_t > 60.0 {
            out.push((r.t, 0.0, 0));
        }
        let d = out.last_mut().unwrap();
        d.1 += f(r);
        d.2 += 1;
        last_t = r.t;
    }
    out.into_iter().map(|(t, s, n)| (t, s / n as f64)).collect()
}

#[test]
fn z_drift_of_a_fixed_point_stays_within_5_um_after_correction() {
    let cell = cell();
    let pose = cell.tracker.clone().unwrap().pose;
    let tool = cell.machine.tool_offset;
    let sim = Simulation::new(cell, 8.0 * HOUR, 11).unwrap();

    let mut known = ThermalCompensator { scale: ThermalScaleCompensator::new(11.5e-6, 0.0, 20.0, vec![]).unwrap(), growth: vec![growth(G_TRUE, TAU_TRUE)], workpiece: None };
    let mut column_readings = Vec::new();
    let mut readings = Vec::new();
    for (s, truth) in sim.samples_with_truth() {
        match (s, truth) {
            (Sample::Temperature(t), _) if &*t.sensor == "column" => {
                known.observe("column", t.t, t.value, t.variance);
                column_readings.push((t.t, t.value, t.variance));
            }
            (Sample::Tracker(m), SampleTruth::Tracker(tt)) if m.target_id == Some(0) && m.status == TrackerStatus::Ok => {
                let measured = pose.rotation * m.point + pose.translation;
                let error = measured - (tt.commanded + tool);
                let cov = pose.rotation * m.covariance * pose.rotation.transpose();
                let (drift, _) = known.drift(&tt.commanded, &|_| None).unwrap();
                readings.push(Reading { t: m.t, error, cov, predicted_z: drift.z });
            }
            _ => {}
        }
    }
    let raw = dwell_means(&readings, |r| r.error.z);
    assert_eq!(raw.len(), 16, "program point 0 is visited once per 30-min cycle");
    let raw_span = raw.iter().map(|d| d.1).fold(f64::NEG_INFINITY, f64::max) - raw.iter().map(|d| d.1).fold(f64::INFINITY, f64::min);
    eprintln!("uncorrected Z drift span {:.2} µm", raw_span * 1e6);
    assert!(raw_span > 8e-6, "the column growth must be visible uncorrected: {raw_span:e} m");

    // known g and τ: every dwell within ±5 µm
    for (t, z) in dwell_means(&readings, |r| r.error.z - r.predicted_z) {
        eprintln!("known   t = {:.2} h: corrected Z error {:+.2} µm", t / HOUR, z * 1e6);
        assert!(z.abs() <= 5e-6, "at {:.2} h the corrected Z error is {:.2} µm", t / HOUR, z * 1e6);
    }

    // online fit on hours 0–4, held-out hours 4–8
    let mut fit = GrowthFit::new(Vector3::new(0.0, 0.0, -1.0), 20.0, (60.0, 1e5), 1_000_000).unwrap();
    let mut next = 0;
    for r in readings.iter().filter(|r| r.t < 4.0 * HOUR) {
        while next < column_readings.len() && column_readings[next].0 <= r.t {
            let (t, v, var) = column_readings[next];
            fit.add_reading(t, v, var);
            next += 1;
        }
        fit.add_observation(r.t, &r.error, &r.cov).unwrap();
    }
    let f = fit.fit().unwrap();
    let (ug, utau) = (f.covariance[(1, 1)].sqrt(), f.covariance[(2, 2)].sqrt());
    eprintln!("fit on 0–4 h: g = {:.3} ± {:.3} µm/K, τ = {:.0} ± {:.0} s, c = {:.2} µm, {} readings", f.coefficient * 1e6, ug * 1e6, f.time_constant, utau, f.offset * 1e6, f.observations);
    assert!((f.coefficient - G_TRUE).abs() <= 3.0 * ug, "g {} ± {ug}", f.coefficient);
    assert!((f.time_constant - TAU_TRUE).abs() <= 3.0 * utau, "τ {} ± {utau}", f.time_constant);
    assert!(!f.at_bound);

    let mut fitted = growth(f.coefficient, f.time_constant);
    fitted.use_fitted(f.coefficient, f.time_constant, Matrix2::new(ug * ug, 0.0, 0.0, utau * utau), fit.lag(f.time_constant)).unwrap();
    let mut held_out = Vec::new();
    let mut next = 0;
    for r in &readings {
        while next < column_readings.len() && column_readings[next].0 <= r.t {
            let (t, v, var) = column_readings[next];
            fitted.observe(t, v, var);
            next += 1;
        }
        if r.t >= 4.0 * HOUR {
            let d = fitted.drift(&Vector3::zeros()).unwrap().displacement;
            // y = −error_z = c + g·ΔT_f, so error_z − drift_z + c is the point's remaining Z drift
            held_out.push(Reading { t: r.t, error: r.error, cov: r.cov, predicted_z: d.z - f.offset });
        }
    }
    let dwells = dwell_means(&held_out, |r| r.error.z - r.predicted_z);
    assert_eq!(dwells.len(), 8);
    for (t, z) in dwells {
        eprintln!("fitted  t = {:.2} h: corrected Z drift {:+.2} µm", t / HOUR, z * 1e6);
        assert!(z.abs() <= 5e-6, "held-out {:.2} h: corrected Z drift {:.2} µm", t / HOUR, z * 1e6);
    }
}
