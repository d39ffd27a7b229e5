//! A declared model of several terms: stacked parameters, summed displacement and Jacobian.

use metrocell_physics::model::TermModel;
use metrocell_physics::{Frame, Signals, TermConfig};
use nalgebra::Vector3;

fn yaml(t: &str) -> Vec<TermConfig> {
    serde_yaml::from_str(t).unwrap()
}

#[test]
fn stacked_model_sums_displacements_and_stacks_jacobians() {
    let m = TermModel::from_configs(&yaml(
        "- {id: positioning, options: {axis: x, order: 1, travel: [0 m, 1 m]}, params: {c0: 2 um, c1: 5 um}}\n\
         - {id: squareness, options: {pair: xy}, params: {s: 0.1 mrad}}\n\
         - {id: tracker_warmup, params: {offset: 0, amplitude: 19 um, time_constant: 30 min}}\n",
    ))
    .unwrap();
    let names: Vec<String> = m.param_specs().into_iter().map(|p| p.name).collect();
    assert_eq!(
        names,
        [
            "positioning[x].c0",
            "positioning[x].c1",
            "squareness[xy].s",
            "tracker_warmup.offset",
            "tracker_warmup.amplitude",
            "tracker_warmup.time_constant"
        ]
    );
    let p = m.params();
    let s = Signals::default().with_positions(Vector3::new(0.75, 0.2, 0.0));
    let (d, j) = m.displacement(Frame::Machine, &p, &s).unwrap();
    // x: 2 µm + 5 µm·u(0.75) with u = 0.5, minus y·s = 0.2·1e-4 = 20 µm
    assert!((d.x - (2e-6 + 2.5e-6 - 20e-6)).abs() < 1e-15, "{}", d.x);
    assert_eq!(j.shape(), (3, 6));
    assert!((j[(0, 1)] - 0.5).abs() < 1e-15 && (j[(0, 2)] + 0.2).abs() < 1e-15);
    assert!(
        j.columns(3, 3).iter().all(|v| *v == 0.0),
        "range terms do not enter the displacement"
    );
    assert!(m.displacement(Frame::Machine, &p[..5], &s).is_err());
    let dup = TermModel::from_configs(&yaml("- {id: backlash, options: {axis: x}, use_defaults: true}\n- {id: backlash, options: {axis: x}, use_defaults: true}\n"));
    assert!(dup.unwrap_err().to_string().contains("backlash[x]"));
}
