//! Seed 002 (delta ArUco calibration digest), fixtures T5–T7, plus parameter-Jacobian checks.

use metrocell_kinematics::delta::{DeltaGeometry, DELTA_PARAMETER_COUNT};
use metrocell_kinematics::KinematicsError;
use metrocell_solver::numeric_jacobian::{
    central_difference, max_relative_difference, steps_with_unit_floor, Order,
};
use nalgebra::{DMatrix, DVector, SMatrix, Vector3};

const MM: f64 = 1e-3;

fn kossel() -> DeltaGeometry {
    DeltaGeometry::new(215.0 * MM, 105.6 * MM).unwrap()
}

fn round_to(v: f64, digits: i32) -> f64 {
    let s = 10f64.powi(digits);
    (v * s).round() / s
}

#[test]
fn t5_tower_positions_match_seed_to_4_decimals_mm() {
    let g = kossel();
    let expected = [(-91.4523, -52.8), (91.4523, -52.8), (0.0, 105.6)];
    for (t, (ex, ey)) in expected.iter().enumerate() {
        let xy = g.tower_xy(t) / MM;
        assert_eq!(round_to(xy.x, 4), *ex, "tower {t} x");
        assert_eq!(round_to(xy.y, 4), *ey, "tower {t} y");
    }
}

#[test]
fn t6_carriage_heights_match_seed_to_4_decimals_mm() {
    let g = kossel();
    let cases = [
        ([0.0, 0.0, 0.0], [187.2796, 187.2796, 187.2796]),
        ([0.0, 50.0, 0.0], [165.2079, 165.2079, 207.6864]),
        ([50.0, 0.0, 10.0], [163.0634, 214.2520, 190.4817]),
    ];
    for (p, expected) in cases {
        let q = g.inverse(&(Vector3::from(p) * MM)).unwrap();
        for t in 0..3 {
            assert_eq!(
                round_to(q[t] / MM, 4),
                expected[t],
                "effector {p:?} tower {t}: {}",
                q[t] / MM
            );
        }
    }
}

#[test]
fn t7_forward_of_inverse_round_trips_to_1e_9_m() {
    let g = kossel();
    let p = Vector3::new(10.0, 20.0, 5.0) * MM;
    let back = g.forward(&g.inverse(&p).unwrap()).unwrap();
    assert!((back - p).norm() < 1e-9, "{back:?}");
}

fn perturbed() -> DeltaGeometry {
    let mut g = kossel();
    g.tower_angle_trim = [
        0.3f64.to_radians(),
        -0.2f64.to_radians(),
        0.1f64.to_radians(),
    ];
    g.radius_trim = [0.2 * MM, -0.1 * MM, 0.05 * MM];
    g.rod_trim = [0.1 * MM, -0.3 * MM, 0.2 * MM];
    g.endstop = [-0.4 * MM, 0.7 * MM, 0.2 * MM];
    g
}

#[test]
fn round_trip_with_trims_and_endstops_over_the_bed() {
    let g = perturbed();
    for &x in &[-60.0, 0.0, 45.0] {
        for &y in &[-70.0, 0.0, 30.0] {
            for &z in &[0.0, 120.0] {
                let p = Vector3::new(x, y, z) * MM;
                let back = g.forward(&g.inverse(&p).unwrap()).unwrap();
                assert!((back - p).norm() < 1e-9, "{p:?} -> {back:?}");
            }
        }
    }
}

#[test]
fn unreachable_and_non_intersecting_inputs_are_errors() {
    let g = kossel();
    let err = g.inverse(&Vector3::new(0.5, 0.0, 0.0)).unwrap_err();
    assert!(matches!(err, KinematicsError::DeltaUnreachable { .. }));
    let err = g.forward(&[0.0, 0.0, 1.0]).unwrap_err();
    assert!(matches!(err, KinematicsError::DeltaNoIntersection { .. }));
    assert!(g.inverse(&Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
    assert!(DeltaGeometry::new(-0.2, 0.1).is_err());
}

fn to_dmatrix(m: &SMatrix<f64, 3, DELTA_PARAMETER_COUNT>) -> DMatrix<f64> {
    DMatrix::from_iterator(3, DELTA_PARAMETER_COUNT, m.iter().cloned())
}

#[test]
fn parameter_jacobians_match_central_differences_to_1e_6() {
    let g = perturbed();
    let theta0 = DVector::from_iterator(DELTA_PARAMETER_COUNT, g.to_vector().iter().cloned());
    for p in [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(40.0, -30.0, 15.0) * MM,
        Vector3::new(-55.0, 60.0, 80.0) * MM,
    ] {
        // IK parameter Jacobian.
        let ik = |th: &[f64]| {
            let gg = DeltaGeometry::from_vector(&SMatrix::from_iterator(th.iter().cloned()));
            gg.inverse(&p).ok().map(|q| DVector::from_row_slice(&q))
        };
        let fd = central_difference(
            ik,
            theta0.as_slice(),
            &steps_with_unit_floor(theta0.as_slice(), 1e-7),
            Order::Second,
        )
        .unwrap();
        let an = to_dmatrix(&g.inverse_parameter_jacobian(&p).unwrap());
        let rel = max_relative_difference(&an, &fd);
        assert!(rel < 1e-6, "IK param Jacobian at {p:?}: rel diff {rel:e}");

        // FK parameter Jacobian with carriage heights fixed.
        let q = g.inverse(&p).unwrap();
        let fk = |th: &[f64]| {
            let gg = DeltaGeometry::from_vector(&SMatrix::from_iterator(th.iter().cloned()));
            gg.forward(&q)
                .ok()
                .map(|v| DVector::from_row_slice(v.as_slice()))
        };
        let fd = central_difference(
            fk,
            theta0.as_slice(),
            &steps_with_unit_floor(theta0.as_slice(), 1e-7),
            Order::Second,
        )
        .unwrap();
        let an = to_dmatrix(&g.forward_parameter_jacobian(&q).unwrap());
        let rel = max_relative_difference(&an, &fd);
        assert!(rel < 1e-6, "FK param Jacobian at {p:?}: rel diff {rel:e}");
    }
}

#[test]
fn t17_tower_c_angle_trim_skews_bars_as_seed_predicts() {
    // Firmware nominal, true tower C at +0.5°: commanded 50 mm bars from the centre toward each tower.
    let firmware = kossel();
    let mut truth = kossel();
    truth.tower_angle_trim[2] = 0.5f64.to_radians();
    let centre = truth
        .forward(&firmware.inverse(&Vector3::zeros()).unwrap())
        .unwrap();
    let expected = [(210.25, 50.1365), (330.25, 49.8651), (90.00, 50.0011)];
    for (t, (exp_dir, exp_len)) in expected.iter().enumerate() {
        let a = firmware.tower_angle(t);
        let cmd = Vector3::new(a.cos(), a.sin(), 0.0) * 50.0 * MM;
        let end = truth.forward(&firmware.inverse(&cmd).unwrap()).unwrap();
        let d = (end - centre).xy();
        let dir = d.y.atan2(d.x).to_degrees().rem_euclid(360.0);
        assert_eq!(round_to(dir, 2), *exp_dir, "bar {t} direction {dir}");
        assert_eq!(
            round_to(d.norm() / MM, 4),
            *exp_len,
            "bar {t} length {}",
            d.norm() / MM
        );
    }
}

/// Effector xy reached by the true machine when the firmware (nominal `firmware`) is commanded to `cmd`.
fn printed(firmware: &DeltaGeometry, truth: &DeltaGeometry, cmd: Vector3<f64>) -> Vector3<f64> {
    truth.forward(&firmware.inverse(&cmd).unwrap()).unwrap()
}

#[test]
fn t14_t15_true_move_toward_tower_c_with_wrong_rod() {
    let firmware = kossel();
    for (true_rod, expected) in [(214.0, 49.70068), (216.0, 50.29886)] {
        let truth = DeltaGeometry::new(true_rod * MM, 105.6 * MM).unwrap();
        let a = printed(&firmware, &truth, Vector3::zeros());
        let b = printed(&firmware, &truth, Vector3::new(0.0, 50.0, 0.0) * MM);
        let l = (b - a).xy().norm() / MM;
        assert_eq!(round_to(l, 5), expected, "true D {true_rod}: L = {l}");
    }
}

#[test]
fn t16_printed_bar_length_with_wrong_rod() {
    let firmware = kossel();
    for (true_rod, expected) in [(214.0, 99.3768), (216.0, 100.6222)] {
        let truth = DeltaGeometry::new(true_rod * MM, 105.6 * MM).unwrap();
        for dir in [Vector3::x(), Vector3::y()] {
            let a = printed(&firmware, &truth, -dir * 50.0 * MM);
            let b = printed(&firmware, &truth, dir * 50.0 * MM);
            let l = (b - a).xy().norm() / MM;
            assert_eq!(
                round_to(l, 4),
                expected,
                "true D {true_rod} along {dir:?}: {l}"
            );
        }
    }
}
