//! Calibration on seeded synthetic views: recovered parameters within their reported uncertainty
//! of the truth, σ estimated at the injected noise, and bad views rejected with the right reason.

mod common;
use common::*;
use metrocell_camera_model::{calibrate, CalibrationFlags, LensModel, RejectionReason, View};

fn z_scores(model: LensModel, seeds: &[u64], sigma: f64) -> Vec<f64> {
    let truth = if model == LensModel::Fisheye {
        fisheye_truth()
    } else {
        pinhole_truth()
    };
    let dist = if model == LensModel::Fisheye {
        (0.2, 0.45)
    } else {
        (0.35, 0.7)
    };
    let mut zs = Vec::new();
    for &seed in seeds {
        let (views, poses) = synthetic_views(&truth, 20, sigma, seed, dist);
        let cal = calibrate(
            &views,
            (truth.width, truth.height),
            model,
            &CalibrationFlags::default(),
        )
        .unwrap();
        assert!(
            cal.rejected.is_empty(),
            "seed {seed}: unexpected rejections {:?}",
            cal.rejected
        );
        // σ from the residuals with 2N − P dof estimates the injected noise.
        let dof = (2 * cal.n_points - cal.n_free_params) as f64;
        let chi_tol = 3.0 * (2.0 / dof).sqrt() * sigma; // 3σ of the σ estimate, roughly
        assert!(
            (cal.sigma_px - sigma).abs() < chi_tol.max(0.02 * sigma),
            "seed {seed}: σ̂ = {} vs injected {sigma}",
            cal.sigma_px
        );
        let est = cal.camera.params();
        let tru = truth.params();
        let z: Vec<f64> = (0..est.len())
            .map(|i| (est[i] - tru[i]) / cal.param_std[i])
            .collect();
        println!(
            "{model:?} seed {seed}: σ̂ {:.4} px, rms {:.4} px, z = {:?}",
            cal.sigma_px,
            cal.rms_px,
            z.iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
        println!(
            "   f = {:.3} ± {:.3} (truth {}), c = ({:.3} ± {:.3}, {:.3} ± {:.3})",
            est[0], cal.param_std[0], tru[0], est[2], cal.param_std[2], est[3], cal.param_std[3]
        );
        // Poses too: translation of every view within 4σ.
        for (v, p) in cal.views.iter().zip(&poses) {
            for a in 0..3 {
                let zt = (v.pose.translation[a] - p.translation[a]) / v.pose_std[a];
                assert!(
                    zt.abs() < 4.0,
                    "seed {seed} view {} t[{a}] off by {zt:.2} σ",
                    v.index
                );
            }
        }
        zs.extend(z);
    }
    zs
}

fn check(zs: &[f64], what: &str) {
    let mean_z2 = zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64;
    let worst = zs.iter().fold(0.0f64, |a, z| a.max(z.abs()));
    println!(
        "{what}: {} parameter errors, mean z² = {mean_z2:.3}, max |z| = {worst:.2}",
        zs.len()
    );
    assert!(
        worst < 3.5,
        "{what}: a parameter is {worst:.2} σ from the truth"
    );
    assert!(
        mean_z2 > 0.4 && mean_z2 < 1.8,
        "{what}: mean z² {mean_z2} (uncertainties mis-scaled)"
    );
}

#[test]
fn brown_conrady_parameters_within_uncertainty_of_truth() {
    let zs = z_scores(
        LensModel::BrownConrady,
        &[101, 102, 103, 104, 105, 106],
        0.2,
    );
    check(&zs, "Brown–Conrady");
}

#[test]
fn fisheye_parameters_within_uncertainty_of_truth() {
    let zs = z_scores(LensModel::Fisheye, &[201, 202, 203, 204], 0.15);
    check(&zs, "fisheye");
}

#[test]
fn bad_views_are_rejected_with_reasons() {
    let truth = pinhole_truth();
    let (mut views, _) = synthetic_views(&truth, 14, 0.2, 77, (0.35, 0.7));
    // View 3: 3 px noise on top (an outlier view); view 5: only 5 points; view 8: collinear points.
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(5);
    for p in views[3].image_points.iter_mut() {
        p[0] += 3.0 * gauss(&mut rng);
        p[1] += 3.0 * gauss(&mut rng);
    }
    views[5] = View {
        object_points: views[5].object_points[..5].to_vec(),
        image_points: views[5].image_points[..5].to_vec(),
    };
    views[8] = View {
        object_points: views[8].object_points[..9].to_vec(),
        image_points: views[8].image_points[..9].to_vec(),
    };
    let cal = calibrate(
        &views,
        (truth.width, truth.height),
        LensModel::BrownConrady,
        &CalibrationFlags::default(),
    )
    .unwrap();
    println!("{:#?}", cal.rejected);
    assert_eq!(cal.rejected.len(), 3);
    assert!(matches!(
        cal.rejected[0],
        metrocell_camera_model::RejectedView {
            index: 3,
            reason: RejectionReason::OutlierRms { .. }
        }
    ));
    assert!(
        matches!(
            cal.rejected[1].reason,
            RejectionReason::TooFewPoints { got: 5, needed: 8 }
        ) && cal.rejected[1].index == 5
    );
    assert!(
        matches!(
            cal.rejected[2].reason,
            RejectionReason::DegenerateHomography(_)
        ) && cal.rejected[2].index == 8
    );
    assert_eq!(cal.views.len(), 11);
    assert!(cal.rms_px < 0.35, "RMS after rejection {}", cal.rms_px);
    // Nothing usable is an error, not a panic.
    let err = calibrate(
        &views[5..6],
        (truth.width, truth.height),
        LensModel::BrownConrady,
        &CalibrationFlags::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("TooFewPoints"), "{err}");
}

#[test]
fn initial_guess_and_fixed_coefficients() {
    let truth = fisheye_truth();
    let (views, _) = synthetic_views(&truth, 15, 0.2, 301, (0.2, 0.45));
    let free = calibrate(
        &views,
        (truth.width, truth.height),
        LensModel::Fisheye,
        &CalibrationFlags::default(),
    )
    .unwrap();
    // Starting from a perturbed guess converges to the same optimum.
    let guess = truth
        .with_params(&[430.0, 430.0, 630.0, 490.0, 0.0, 0.0, 0.0, 0.0])
        .unwrap();
    let flags = CalibrationFlags {
        initial_guess: Some(guess),
        ..Default::default()
    };
    let guessed = calibrate(
        &views,
        (truth.width, truth.height),
        LensModel::Fisheye,
        &flags,
    )
    .unwrap();
    for (a, b) in free.camera.params().iter().zip(guessed.camera.params()) {
        assert!((a - b).abs() < 1e-6 * (1.0 + a.abs()), "{a} vs {b}");
    }
    // Fixing k4 at 0 keeps it there with zero uncertainty, and costs a little RMS.
    let flags = CalibrationFlags {
        fixed_distortion: vec![3],
        ..Default::default()
    };
    let fixed = calibrate(
        &views,
        (truth.width, truth.height),
        LensModel::Fisheye,
        &flags,
    )
    .unwrap();
    assert_eq!(fixed.camera.params()[7], 0.0);
    assert_eq!(fixed.param_std[7], 0.0);
    assert_eq!(fixed.n_free_params + 1, free.n_free_params);
    assert!(fixed.rms_px >= free.rms_px);
    // A guess of the other lens model is refused.
    let flags = CalibrationFlags {
        initial_guess: Some(pinhole_truth()),
        ..Default::default()
    };
    assert!(calibrate(
        &views,
        (truth.width, truth.height),
        LensModel::Fisheye,
        &flags
    )
    .is_err());
}
