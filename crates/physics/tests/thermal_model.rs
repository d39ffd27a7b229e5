//! The lumped shift thermal model: exact first-order response, determinism, validation.

use metrocell_physics::thermal::shift_model::*;

fn single_node(walk: f64, noise: f64) -> ShiftThermalModel {
    ShiftThermalModel {
        ambient: AmbientCycle {
            mean: 20.0,
            amplitude: 0.0,
            period: 86_400.0,
            phase: 0.0,
            drift: 0.0,
            walk_std: walk,
        },
        sources: vec![HeatSource {
            name: "spindle".into(),
            duty: vec![DutySegment {
                start: 0.0,
                end: 1e9,
                level: 1.0,
            }],
        }],
        nodes: vec![StructureNode {
            name: "head".into(),
            time_constant: 1200.0,
            heating: vec![("spindle".into(), 3.0)],
            initial: None,
        }],
        sensors: vec![ThermalSensor {
            name: "head".into(),
            location: SensorLocation::Node("head".into()),
            bias: 0.0,
            noise_std: noise,
        }],
    }
}

#[test]
fn node_follows_the_exact_first_order_step_response() {
    let log = single_node(0.0, 0.0).simulate(3600.0, 10.0, 1).unwrap();
    for (k, t) in log.times.iter().enumerate() {
        let expect = 20.0 + 3.0 * (1.0 - (-t / 1200.0).exp());
        assert!((log.sensors["head"][k] - expect).abs() < 1e-12, "t = {t}");
    }
    // after τ: 63.2 % of the 3 K steady-state rise
    assert!((log.at("head", 1200.0).unwrap() - (20.0 + 3.0 * 0.632_120_558_8)).abs() < 1e-9);
}

#[test]
fn ambient_cycle_and_drift_are_reproduced_without_noise() {
    let mut m = single_node(0.0, 0.0);
    m.ambient = AmbientCycle {
        mean: 20.0,
        amplitude: 1.0,
        period: 7200.0,
        phase: 0.3,
        drift: 1e-5,
        walk_std: 0.0,
    };
    let log = m.simulate(7200.0, 60.0, 0).unwrap();
    for (k, t) in log.times.iter().enumerate() {
        let expect = 20.0 + (std::f64::consts::TAU * t / 7200.0 + 0.3).sin() + 1e-5 * t;
        assert!((log.truth["ambient"][k] - expect).abs() < 1e-12);
    }
}

#[test]
fn deterministic_given_a_seed() {
    let m = ShiftThermalModel::example_machine_shift();
    let a = m.simulate(8.0 * 3600.0, 30.0, 42).unwrap();
    let b = m.simulate(8.0 * 3600.0, 30.0, 42).unwrap();
    let c = m.simulate(8.0 * 3600.0, 30.0, 43).unwrap();
    assert_eq!(a, b);
    assert_ne!(a.sensors["column"], c.sensors["column"]);
    // the spindle head heats faster and further than the column during the first work block
    let t = 2.5 * 3600.0;
    let head = a.truth["head"][(t / 30.0) as usize] - a.truth["ambient"][(t / 30.0) as usize];
    let column = a.truth["column"][(t / 30.0) as usize] - a.truth["ambient"][(t / 30.0) as usize];
    assert!(
        head > 3.0 && column > 1.0 && head > column,
        "head {head}, column {column}"
    );
    // sensor noise is at its stated level (0.02 K) around the truth
    let res: Vec<f64> = a.sensors["head"]
        .iter()
        .zip(&a.truth["head"])
        .map(|(s, t)| s - t)
        .collect();
    let sd = (res.iter().map(|r| r * r).sum::<f64>() / res.len() as f64).sqrt();
    assert!((sd - 0.02).abs() < 0.002, "noise sd {sd}");
    let h = a.history_until("column", 3600.0).unwrap();
    assert_eq!(h.samples.len(), 121);
}

#[test]
fn invalid_models_are_rejected_with_names() {
    let mut m = single_node(0.0, 0.0);
    m.nodes[0].heating[0].0 = "laser".into();
    let e = m.simulate(10.0, 1.0, 0).unwrap_err().to_string();
    assert!(
        e.contains("node `head`") && e.contains("unknown source `laser`"),
        "{e}"
    );
    let mut m = single_node(0.0, 0.0);
    m.nodes[0].time_constant = 0.0;
    assert!(m
        .simulate(10.0, 1.0, 0)
        .unwrap_err()
        .to_string()
        .contains("time_constant"));
    let m = single_node(0.0, 0.0);
    assert!(m.simulate(10.0, 0.0, 0).is_err());
    let mut m = single_node(0.0, 0.0);
    m.sensors[0].location = SensorLocation::Node("bed".into());
    assert!(m
        .simulate(10.0, 1.0, 0)
        .unwrap_err()
        .to_string()
        .contains("unknown node `bed`"));
}

/// The simulator path: shift model → signals → thermal_growth term with lag.
#[test]
fn shift_log_drives_a_lagged_growth_term() {
    use metrocell_physics::catalog::{configure, example_config};
    use metrocell_physics::{Signals, TermId};
    let log = ShiftThermalModel::example_machine_shift()
        .simulate(4.0 * 3600.0, 60.0, 3)
        .unwrap();
    let mut s = Signals::default();
    log.fill_signals(3.0 * 3600.0, &mut s);
    assert_eq!(
        s.timeline
            .as_ref()
            .unwrap()
            .history("column", s.time)
            .unwrap()
            .samples
            .len(),
        181
    );
    assert_eq!(
        s.temperatures["column"],
        log.at("column", 3.0 * 3600.0).unwrap()
    );
    let t = configure(&example_config(TermId::ThermalGrowth)).unwrap(); // direction −z, g 11.5 µm/K, τ 1800 s
    let d = t.term.predict(&t.params, &s).unwrap().value;
    // the column is warmer than 20 °C after 2.5 h of work → the head drops (−z)
    assert!(d[2] < -1e-6 && d[2] > -100e-6, "{}", d[2]);
}
