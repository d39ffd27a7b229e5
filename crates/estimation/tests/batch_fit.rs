//! Batch fit on points the shared model predicts at known parameters, plus noise: the declared
//! parameters come back within their stated uncertainty, the residual is at the noise floor,
//! and the tracker pose is found from any placement.

use metrocell_estimation::{
    fit, rms, FitOptions, MeasurementRecord, RecordFrame, RecordKind, RecordSet,
};
use metrocell_model::ParameterSetup;
use metrocell_physics::Signals;
use metrocell_twin::Cell;
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const CELL: &str = r#"
name: fit_test
machine:
  family: cartesian
  stacking: XFYZ
  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}
  tool_offset: [0 mm, 0 mm, -150 mm]
sensors:
  tracker:
    pose: {translation: [-863.527 mm, 194.373 mm, 677.782 mm], euler_xyz: [0.0339 deg, 0.0343 deg, 59.4652 deg]}
    rate: 10 Hz
    range_noise: {constant: 4 um, per_metre: 0.8 um/m}
    angular_noise: 3 urad
environment:
  ambient: {mean: 20 degC}
  air: {pressure: 101.3 kPa, humidity: 45}
program:
  grid:
    x: {from: 0 mm, to: 800 mm, count: 3}
    y: {from: 0 mm, to: 500 mm, count: 3}
    z: {from: 0 mm, to: 400 mm, count: 3}
  feed_rate: 100 mm/s
  dwell: 1 s
terms:
  - id: positioning
    options: {axis: x, order: 3}
    params: {c0: 0 um, c1: 12 um, c2: -8 um, c3: 5 um}
  - id: squareness
    options: {pair: xy}
    params: {s: 20 urad}
  - id: backlash
    options: {axis: y}
    params: {reversal: 9 um}
"#;

fn records(cell: &Cell, sigma: f64, seed: u64) -> RecordSet {
    let instruments = cell.tracker_terms().unwrap();
    let model = cell.forward_model(&instruments).unwrap();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma).unwrap();
    let mut out = Vec::new();
    for i in 0..6 {
        for j in 0..5 {
            for k in 0..3 {
                let q = [
                    0.8 * i as f64 / 5.0,
                    0.5 * j as f64 / 4.0,
                    0.4 * k as f64 / 2.0,
                ];
                for approach in [1.0, -1.0] {
                    let mut s = Signals {
                        air_temperature: Some(20.0),
                        air_pressure: Some(101_300.0),
                        air_humidity: Some(45.0),
                        ..Signals::default()
                    };
                    model.set_motion(&mut s, &q, &[0.0; 3], &[approach; 3]);
                    let tool = model.tool_state(&p, &kin, &q, &mut s, None).unwrap();
                    let pred = model.tracker(&p, &tool, &mut s).unwrap();
                    let measured =
                        pred.measured_point() + Vector3::from_fn(|_, _| noise.sample(&mut rng));
                    s.target_point = None;
                    s.tracker_range = None;
                    out.push(MeasurementRecord {
                        time: out.len() as f64,
                        point_id: format!("p{i}{j}{k}"),
                        channel: "tracker".into(),
                        q: q.to_vec(),
                        measured,
                        covariance: Matrix3::identity() * sigma * sigma,
                        signals: s,
                        kind: RecordKind::Point,
                    });
                }
            }
        }
    }
    RecordSet {
        check: Vec::new(),
        frame: RecordFrame::Instrument("tracker".into()),
        records: out,
        rejected: vec![],
        sources: vec![],
    }
}

/// The test cell with its terms at zero: the model a user starts a fit from.
fn zeroed_model_cell() -> Cell {
    let mut cell = Cell::from_yaml_str(CELL, "fit_test").unwrap();
    for t in &mut cell.terms.terms {
        t.params.iter_mut().for_each(|v| *v = 0.0);
    }
    cell
}

/// Every parameter free but refraction (not estimated here) and positioning's constant (the
/// tracker's translation).
fn declared_setup(model: &metrocell_model::ForwardModel) -> ParameterSetup {
    let mut setup = ParameterSetup::all_free(model);
    for (k, n) in setup.names.clone().iter().enumerate() {
        if n.starts_with("refraction") || n == "positioning[x].c0" {
            setup.free[k] = false;
        }
    }
    setup
}

#[test]
fn declared_parameters_come_back_within_their_uncertainty() {
    let truth = Cell::from_yaml_str(CELL, "fit_test").unwrap();
    let sigma = 5e-6;
    let data = records(&truth, sigma, 7);
    // the model: the same terms at zero, the tracker placed roughly (10 cm, 5° off)
    let mut model_cell = zeroed_model_cell();
    let tr = model_cell.tracker.as_mut().unwrap();
    tr.pose = metrocell_model::InstrumentPose::from_euler_xyz(
        tr.pose.translation + Vector3::new(0.1, -0.1, 0.05),
        [0.0, 0.0, 55f64.to_radians()],
    );
    let instruments = model_cell.tracker_terms().unwrap();
    let model = model_cell.forward_model(&instruments).unwrap();
    let setup = declared_setup(&model);
    let f = fit(&model, &setup, &data, None, &FitOptions::default()).unwrap();
    let after = rms(&f.residuals_after);
    assert!(
        (after / sigma - 1.0).abs() < 0.1,
        "residual RMS {after:e} vs noise {sigma:e}"
    );
    assert!(
        rms(&f.residuals_before) > 1.5 * sigma,
        "before {:e}",
        rms(&f.residuals_before)
    );
    let truth_instruments = truth.tracker_terms().unwrap();
    let truth_model = truth.forward_model(&truth_instruments).unwrap();
    let true_values = truth_model.params();
    let mut within = 0;
    let mut checked = 0;
    for (k, p) in f.parameters.iter().enumerate() {
        if !p.free {
            continue;
        }
        let u = p.sigma.expect("identifiable");
        let z = (p.value - true_values[k]) / u;
        assert!(
            z.abs() < 4.0,
            "{} = {:e} ± {:e}, truth {:e}",
            p.name,
            p.value,
            u,
            true_values[k]
        );
        checked += 1;
        if z.abs() < 3.0 {
            within += 1;
        }
    }
    assert!(
        checked >= 11 && within >= checked - 1,
        "{within} of {checked} within 3σ"
    );
    assert_eq!(
        f.identifiability.rank,
        checked,
        "{:?}",
        f.identifiability.describe()
    );
}

/// A prior (value, σ) on a parameter enters the fit as one more observation: with a prior as
/// strong as the data (σ_p = the data's σ), the estimate is the precision-weighted mean of the
/// data-only estimate and the prior's value, and its σ shrinks by √2 — linear-Gaussian algebra,
/// checked through `fit` on the squareness of the test cell.
#[test]
fn a_prior_combines_with_the_data_by_precision() {
    let truth = Cell::from_yaml_str(CELL, "fit_test").unwrap();
    let data = records(&truth, 5e-6, 11);
    let model_cell = zeroed_model_cell();
    let instruments = model_cell.tracker_terms().unwrap();
    let model = model_cell.forward_model(&instruments).unwrap();
    let mut setup = declared_setup(&model);
    let k = setup
        .names
        .iter()
        .position(|n| n == "squareness[xy].s")
        .unwrap();
    let plain = fit(&model, &setup, &data, None, &FitOptions::default()).unwrap();
    let (s_data, u_data) = (
        plain.parameters[k].value,
        plain.parameters[k].sigma.unwrap(),
    );
    // a prior four σ of the data away from the data's estimate, as certain as the data
    let prior = metrocell_model::Prior {
        value: s_data + 4.0 * u_data,
        sigma: u_data,
    };
    setup.priors[k] = Some(prior);
    let with = fit(&model, &setup, &data, None, &FitOptions::default()).unwrap();
    let (s, u) = (with.parameters[k].value, with.parameters[k].sigma.unwrap());
    let expected = (s_data + prior.value) / 2.0;
    assert!((s - expected).abs() < 0.1 * u_data, "with the prior: {s:e}, the precision-weighted mean {expected:e} (data {s_data:e} ± {u_data:e})");
    assert!(
        (u / (u_data / 2f64.sqrt()) - 1.0).abs() < 0.1,
        "σ with the prior {u:e}, expected {:e}",
        u_data / 2f64.sqrt()
    );
}
