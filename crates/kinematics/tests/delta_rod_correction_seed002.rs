//! Seed 002 fixtures T8–T12 (eq. 13 and its closed-form inverse) and T14–T15 (iterating it on a full delta).

use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_kinematics::delta_rod_correction::*;
use metrocell_kinematics::KinematicsError;
use nalgebra::Vector3;

const MM: f64 = 1e-3;
const D0: f64 = 215.0 * MM;
const R: f64 = 105.6 * MM;

fn round_to(v: f64, digits: i32) -> f64 {
    let s = 10f64.powi(digits);
    (v * s).round() / s
}

#[test]
fn t8_identity_and_intermediate_heights() {
    let l = single_arm_move(D0, R, 50.0 * MM, D0).unwrap();
    assert!((l - 50.0 * MM).abs() < 1e-15, "L = {l}");
    assert_eq!(
        round_to(carriage_rise(D0, R, 50.0 * MM).unwrap() / MM, 6),
        20.406821
    );
    assert_eq!(
        round_to(centre_carriage_height(D0, R).unwrap() / MM, 6),
        187.279577
    );
}

#[test]
fn t9_forward_and_sensitivity() {
    assert_eq!(
        round_to(
            single_arm_move(D0, R, 50.0 * MM, 214.0 * MM).unwrap() / MM,
            6
        ),
        49.579918
    );
    assert_eq!(
        round_to(
            single_arm_move(D0, R, 50.0 * MM, 216.0 * MM).unwrap() / MM,
            6
        ),
        50.422652
    );
    for (l_star, expected) in [(50.0, 0.42136), (80.0, 1.17451)] {
        let h = 1e-6;
        let s = (single_arm_move(D0, R, l_star * MM, D0 + h).unwrap()
            - single_arm_move(D0, R, l_star * MM, D0 - h).unwrap())
            / (2.0 * h);
        assert_eq!(round_to(s, 5), expected, "dL/dD at L* = {l_star}");
    }
}

#[test]
fn t10_closed_form_inverse() {
    for (l, expected) in [(50.5, 216.182337), (49.5, 213.809074), (49.9, 214.762499)] {
        let d = rod_from_measured_move(D0, R, 50.0 * MM, l * MM).unwrap();
        assert_eq!(round_to(d / MM, 6), expected);
        let back = single_arm_move(D0, R, 50.0 * MM, d).unwrap();
        assert!((back - l * MM).abs() < 1e-15, "re-inserted L {back}");
    }
}

#[test]
fn t11_average_over_three_arms() {
    let ds: Vec<f64> = [49.94, 50.32, 50.32]
        .iter()
        .map(|l| rod_from_measured_move(D0, R, 50.0 * MM, l * MM).unwrap() / MM)
        .collect();
    let expected = [214.8575, 215.7577, 215.7577];
    for (d, e) in ds.iter().zip(expected) {
        assert_eq!(round_to(*d, 4), e);
    }
    assert_eq!(round_to(ds.iter().sum::<f64>() / 3.0, 4), 215.4576);
}

#[test]
fn t12_infeasible_inputs_raise_errors_not_nan() {
    let err = single_arm_move(D0, R, 100.0 * MM, 216.0 * MM).unwrap_err();
    assert!(matches!(err, KinematicsError::InvalidValue { .. }), "{err}");
    assert!(err.to_string().contains("infeasible"));
}

#[test]
fn t14_t15_iterating_eq13_on_a_full_delta_converges() {
    let cases = [
        (
            214.0,
            49.70068,
            vec![
                214.28809, 214.08335, 214.02415, 214.00700, 214.00203, 214.00059,
            ],
        ),
        (
            216.0,
            50.29886,
            vec![215.70774, 215.91495, 215.97528, 215.99282],
        ),
    ];
    for (true_rod, first_l, estimates) in cases {
        let truth = DeltaGeometry::new(true_rod * MM, R).unwrap();
        let mut firmware_rod = D0;
        for (k, expected) in estimates.iter().enumerate() {
            let firmware = DeltaGeometry::new(firmware_rod, R).unwrap();
            let a = truth
                .forward(&firmware.inverse(&Vector3::zeros()).unwrap())
                .unwrap();
            let b = truth
                .forward(
                    &firmware
                        .inverse(&Vector3::new(0.0, 50.0 * MM, 0.0))
                        .unwrap(),
                )
                .unwrap();
            let l = (b - a).xy().norm();
            if k == 0 {
                assert_eq!(round_to(l / MM, 5), first_l);
            }
            firmware_rod = rod_from_measured_move(firmware_rod, R, 50.0 * MM, l).unwrap();
            assert_eq!(
                round_to(firmware_rod / MM, 5),
                *expected,
                "true D {true_rod}, step {k}"
            );
        }
    }
}

/// T13, a regression guard against the paper's typo: eq. 12 as printed carries an extra
/// "− h*", so with the firmware's own rod (D = D0) it gives L = L* − h* = −137.28 mm for a
/// 50 mm move. The implementation is eq. 13, which gives L = L* there.
#[test]
fn t13_eq12_as_printed_is_not_what_is_implemented() {
    let (d, l_star) = (D0, 50.0 * MM);
    let h_star = centre_carriage_height(D0, R).unwrap();
    let dh = carriage_rise(D0, R, l_star).unwrap();
    let inner = (d * d - R * R).sqrt() + dh;
    let eq12_as_printed = R - (d * d - inner * inner).sqrt() - h_star;
    assert_eq!(round_to(eq12_as_printed / MM, 2), -137.28);
    let implemented = single_arm_move(D0, R, l_star, d).unwrap();
    assert!(
        (implemented - l_star).abs() < 1e-15,
        "eq. 13 at D = D0: {implemented}"
    );
    assert!((implemented - eq12_as_printed).abs() > 0.1);
}
