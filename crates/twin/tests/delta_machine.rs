//! Delta family through crates/kinematics: the twin's machine displacement is
//! FK_true(IK_nominal(q)) − q, and a uniform endstop offset h lifts the effector by exactly h.

mod common;

use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_twin::{MachineKinematics, Sample, SampleTruth, Simulation};

#[test]
fn delta_displacement_is_forward_of_true_geometry_at_nominal_joints() {
    let cell = common::validate(&common::example_file("delta_printer.yaml"));
    let MachineKinematics::Delta(nominal) = cell.machine.kinematics.clone() else {
        panic!("not a delta")
    };
    let mut truth = DeltaGeometry::new(0.25, 0.124).unwrap();
    truth.endstop = [0.3e-3, -0.2e-3, 0.0];
    truth.radius_trim = [0.5e-3, 0.0, -0.3e-3];
    truth.rod_trim = [0.2e-3, 0.0, 0.0];
    assert_eq!(cell.true_delta_geometry(), Some(truth));
    let sim = Simulation::new(cell, 60.0, 1).unwrap();
    let (mut n, mut biggest) = (0, 0.0f64);
    for (s, t) in sim.samples_with_truth() {
        if let (Sample::MachineState(m), SampleTruth::MachineState { displacement }) = (s, t) {
            let q = nalgebra::Vector3::new(m.commanded[0], m.commanded[1], m.commanded[2]);
            let expected = truth.forward(&nominal.inverse(&q).unwrap()).unwrap() - q;
            assert!((displacement - expected).norm() < 1e-12);
            biggest = biggest.max(displacement.norm());
            n += 1;
        }
    }
    assert_eq!(n, 3000);
    // sub-millimetre trims give errors of the same order
    assert!(biggest > 50e-6 && biggest < 2e-3, "largest error {biggest}");
}

#[test]
fn uniform_endstop_offset_lifts_the_effector_by_exactly_that_much() {
    let mut f = common::example_file("delta_printer.yaml");
    f.terms = serde_yaml::from_str("[{id: delta_endstop, params: {endstop_a: 0.25 mm, endstop_b: 0.25 mm, endstop_c: 0.25 mm}}]").unwrap();
    let sim = Simulation::new(common::validate(&f), 30.0, 1).unwrap();
    for (_, t) in sim.samples_with_truth() {
        if let SampleTruth::MachineState { displacement } = t {
            assert!(
                (displacement - nalgebra::Vector3::new(0.0, 0.0, 0.25e-3)).norm() < 1e-12,
                "{displacement:?}"
            );
        }
    }
}

#[test]
fn delta_terms_need_a_delta_and_unreachable_points_are_named() {
    let mut f = common::example_file("quick_demo.yaml");
    f.terms = serde_yaml::from_str(
        "[{id: delta_endstop, params: {endstop_a: 0, endstop_b: 0, endstop_c: 0}}]",
    )
    .unwrap();
    let msg = metrocell_twin::Cell::from_file(&f).unwrap_err().to_string();
    assert!(
        msg.contains("terms[0]") && msg.contains("machine.family: delta"),
        "{msg}"
    );
    let mut f = common::example_file("delta_printer.yaml");
    f.machine.travel.as_mut().unwrap().x = [common::q("-400 mm"), common::q("400 mm")];
    f.program.as_mut().unwrap().grid.as_mut().unwrap().x.to = common::q("350 mm");
    let msg = metrocell_twin::Cell::from_file(&f).unwrap_err().to_string();
    assert!(
        msg.contains("program point") && msg.contains("not reachable by the delta"),
        "{msg}"
    );
}
