//! A reading whose target sits elsewhere on the spindle than the model's tool (a tracker
//! reflector moved to another offset, `Signals::tool_offset_shift`): the forward model puts the
//! nominal point there and sees the angular errors through the longer arm, in the tool state and
//! in the Jacobian path alike; a family whose tool turns refuses it rather than ignore it.

mod common;

use common::term;
use metrocell_model::SignalsBuilderOptions;
use metrocell_model::{ForwardModel, MachineGeometry, MachineKinematics, SignalsBuilder};
use metrocell_physics::model::TermModel;
use metrocell_physics::Signals;
use nalgebra::{DMatrix, Vector3};

fn machine() -> MachineGeometry {
    MachineGeometry {
        kinematics: MachineKinematics::Cartesian("XFYZ".parse().unwrap()),
        travel: [[0.0, 0.8], [0.0, 0.5], [0.0, 0.4]],
        tool_offset: Vector3::new(0.0, 0.0, -0.1),
    }
}

/// Yaw of Y (about z) of a constant 40 µrad, its arm the tool offset and Z's position.
fn yaw_of_y() -> TermModel {
    let mut m = TermModel::default();
    m.push(term("id: angular\noptions: {axis: y, about: z, lever_axes: [z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 0, travel: [0 mm, 500 mm]}\nparams: {c0: 40 urad}\n")).unwrap();
    m
}

#[test]
fn a_moved_target_is_where_the_shift_puts_it_and_sees_the_yaw_through_its_arm() {
    let (machine, terms, none) = (machine(), yaw_of_y(), TermModel::default());
    let model = ForwardModel::new(&machine, &terms, &none).unwrap();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let q = [0.3, 0.2, 0.1];
    let mut s = Signals::default().with_positions(Vector3::new(q[0], q[1], q[2]));
    let at_tool = model.tool_state(&p, &kin, &q, &mut s, None).unwrap();
    // yaw about z with an arm along z moves nothing
    assert!(at_tool.d.norm() < 1e-18, "{:?}", at_tool.d);
    let shift = Vector3::new(0.15, 0.0, 0.0);
    s.tool_offset_shift = Some(shift);
    let moved = model.tool_state(&p, &kin, &q, &mut s, None).unwrap();
    let nominal = Vector3::new(0.3 + 0.15, 0.2, 0.1 - 0.1);
    assert!((moved.nominal.translation.vector - nominal).norm() < 1e-15);
    // the point diagnose's candidate columns read, without running the model: the same
    let point = model.nominal_machine_point(&q, &s).unwrap();
    assert!((point - nominal).norm() < 1e-15, "{point:?}");
    // ε e_z × (0.15 e_x) = 40 µrad · 150 mm along +y = 6 µm
    assert!(
        (moved.d - Vector3::new(0.0, 6e-6, 0.0)).norm() < 1e-15,
        "{:?}",
        moved.d
    );
    // the Jacobian path: the same point, and ∂/∂c0 is the arm's e_z × δ
    let mut lin = DMatrix::zeros(3, p.len());
    let target = model
        .tool_point_jacobian(&p, &kin, &q, &mut s, &mut lin)
        .unwrap();
    assert!((target - moved.target()).norm() < 1e-15);
    assert!((lin.column(0) - Vector3::new(0.0, 0.15, 0.0)).norm() < 1e-15);
}

#[test]
fn a_family_whose_tool_turns_refuses_a_moved_target() {
    let mut five = machine();
    five.kinematics = MachineKinematics::FiveAxis(metrocell_model::FiveAxisMachine {
        geometry: metrocell_kinematics::five_axis::FiveAxisGeometry::new(0.4, 0.1),
        c_limits: [-3.0, 3.0],
    });
    let none = TermModel::default();
    let model = ForwardModel::new(&five, &none, &none).unwrap();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let mut s = Signals {
        tool_offset_shift: Some(Vector3::new(0.0, 0.0, -0.05)),
        ..Default::default()
    };
    let err = model
        .tool_state(&p, &kin, &[0.1, 0.1, 0.1, 0.0, 0.0], &mut s, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("cartesian and delta machines only"), "{err}");
}

#[test]
fn the_recorded_tool_offset_is_a_shift_from_the_models_tool() {
    let mut b = SignalsBuilder::for_machine(&machine(), SignalsBuilderOptions::default());
    assert_eq!(
        b.signals_at(0).tool_offset_shift,
        None,
        "none recorded: the model's tool"
    );
    b.push_tool_offset(1_000_000_000, Vector3::new(0.15, 0.0, -0.1))
        .unwrap();
    b.push_tool_offset(5_000_000_000, Vector3::new(0.0, 0.0, -0.25))
        .unwrap();
    assert_eq!(
        b.signals_at(2_000_000_000).tool_offset_shift,
        Some(Vector3::new(0.15, 0.0, 0.0))
    );
    let later = b.signals_at(6_000_000_000).tool_offset_shift.unwrap();
    assert!((later - Vector3::new(0.0, 0.0, -0.15)).norm() < 1e-15);
    assert_eq!(
        b.tool_offset_at(6_000_000_000),
        Some(Vector3::new(0.0, 0.0, -0.25))
    );
    let mm = b
        .push_tool_offset(0, Vector3::new(0.0, 0.0, -150.0))
        .unwrap_err();
    assert!(mm.contains("is it in mm?"), "{mm}");
    assert!(b
        .push_tool_offset(0, Vector3::new(f64::NAN, 0.0, 0.0))
        .is_err());
}
