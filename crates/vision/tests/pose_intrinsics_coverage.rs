//! Issue 32, item 13: a board pose's stated σ covers the camera calibration's own uncertainty.
//!
//! The calibration's covariance Σ_k of (fx, fy, cx, cy, k1, k2, p1, p2, k3) is what metrocell's
//! calibration states for twelve views of a 9×6 board whose corners it saw with 0.05 px noise.
//! Each of 120 rendered views of the 8×6 test board (random pose, 0.35–0.5 m) is measured with a
//! camera whose parameters are the truth plus an error drawn from Σ_k (as if each view had been
//! taken with its own calibration): the position's error must be within its stated σ at the
//! Gaussian rates — 68.3 % within 1σ and 95.4 % within 2σ, each up to three binomial standard
//! deviations over the 120 views. Without Σ_k (the intrinsics taken as exact, as before) the
//! stated σ covers far less than that, which is what the issue saw: 12 / 9 / 5 µm off while
//! stating ± 0.1 / 0.1 / 0.4 µm.
mod common;

use metrocell_camera_model::{calibrate, CalibrationFlags, LensModel, View};
use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets, render_view, PoseInputs, RenderSettings, TargetFamily};
use nalgebra::{DMatrix, DVector, Point3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller
    let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// The covariance metrocell's calibration states for `cam` from twelve tilted views of a 9×6,
/// 25 mm board with corners seen to 0.05 px.
fn stated_calibration_covariance(
    cam: &metrocell_vision::CameraModel,
    rng: &mut ChaCha8Rng,
) -> DMatrix<f64> {
    let object: Vec<[f64; 3]> = (0..54)
        .map(|k| [(k % 9) as f64 * 0.025, (k / 9) as f64 * 0.025, 0.0])
        .collect();
    let views: Vec<View> = (0..12)
        .map(|k| {
            let (i, j) = (k % 4, k / 4);
            let pose = common::look_at_target(
                [0.1, 0.0625],
                0.40 + 0.01 * k as f64,
                [
                    0.35 * (k as f64 * 1.3).sin(),
                    0.35 * (k as f64 * 0.7).cos(),
                    0.15 * (k as f64 * 2.1).sin(),
                ],
                [-0.09 + 0.06 * i as f64, -0.06 + 0.06 * j as f64],
            );
            let image = object
                .iter()
                .map(|p| {
                    let q =
                        metrocell_vision::camera::project(cam, &pose, &Point3::from(*p)).unwrap();
                    [q.x + 0.05 * normal(rng), q.y + 0.05 * normal(rng)]
                })
                .collect();
            View {
                object_points: object.clone(),
                image_points: image,
            }
        })
        .collect();
    calibrate(
        &views,
        (cam.width, cam.height),
        LensModel::BrownConrady,
        &CalibrationFlags::default(),
    )
    .unwrap()
    .param_covariance
}

/// Position errors of the board pose in units of its stated σ, per view and axis, over `views`
/// views.
fn z_scores(with_intrinsics: bool, views: u64) -> Vec<f64> {
    let truth_cam = common::test_camera();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let sigma_k = stated_calibration_covariance(&truth_cam, &mut rng);
    let chol = sigma_k
        .clone()
        .cholesky()
        .expect("a positive definite calibration covariance")
        .l();
    let family = TargetFamily::parse("checkerboard", Some((8, 6)), Some(0.012)).unwrap();
    let target = common::checkerboard_target();
    let settings = RenderSettings {
        blur_sigma_px: 0.8,
        noise_sigma: 1.0,
        ..Default::default()
    };
    let mut z = Vec::new();
    for view in 0..views {
        let pose = common::look_at_target(
            [0.054, 0.042],
            rng.random_range(0.35..0.5),
            [
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.4..0.4),
            ],
            [rng.random_range(-0.05..0.05), rng.random_range(-0.04..0.04)],
        );
        let rendered = render_view(
            &truth_cam,
            &pose,
            &target,
            &RenderSettings {
                seed: view,
                ..settings
            },
        )
        .unwrap();
        // this view's calibration: the truth plus an error drawn from the stated covariance
        let error = &chol * DVector::from_fn(9, |_, _| normal(&mut rng));
        let p: Vec<f64> = truth_cam
            .params()
            .iter()
            .zip(error.iter())
            .map(|(a, e)| a + e)
            .collect();
        let calibrated = truth_cam.with_params(&p).unwrap();
        let inputs = PoseInputs {
            camera: &calibrated,
            marker_side: None,
            fallback_sigma_px: 0.1,
            intrinsics_covariance: with_intrinsics.then_some(&sigma_k),
        };
        let found = detect_targets(
            &rendered.image,
            &family,
            &DetectorParams::default(),
            Some(inputs),
        )
        .unwrap();
        let board = found
            .first()
            .unwrap_or_else(|| panic!("view {view}: no board"));
        let measured = board
            .pose
            .as_ref()
            .unwrap_or_else(|| panic!("view {view}: no pose"));
        // the pose's origin is the detected corner (0, 0): whichever of the board's it is
        let truth_corners = &rendered.checkerboard_corners[0];
        let k = (0..truth_corners.len())
            .min_by(|&a, &b| {
                (truth_corners[a] - board.corners[0])
                    .norm()
                    .total_cmp(&(truth_corners[b] - board.corners[0]).norm())
            })
            .unwrap();
        let origin =
            pose * Point3::new(0.012 * (1 + k % 8) as f64, 0.012 * (1 + k / 8) as f64, 0.0);
        for axis in 0..3 {
            z.push((measured.position[axis] - origin[axis]) / measured.covariance[7 * axis].sqrt());
        }
    }
    z
}

fn within(z: &[f64], k: f64) -> f64 {
    z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64
}

#[test]
fn the_stated_pose_sigma_covers_the_calibration_uncertainty() {
    let z = z_scores(true, 120);
    let n = (z.len() / 3) as f64; // the three axes of a view share its calibration: count views
    let slack = |p: f64| 3.0 * (p * (1.0 - p) / n).sqrt();
    let (one, two) = (within(&z, 1.0), within(&z, 2.0));
    let worst = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    eprintln!("with the calibration's covariance: {:.1} % within 1σ, {:.1} % within 2σ, worst {worst:.2}σ", 100.0 * one, 100.0 * two);
    assert!(
        (one - 0.683).abs() <= slack(0.683),
        "{:.1} % within 1σ (expected 68.3 ± {:.1} %)",
        100.0 * one,
        100.0 * slack(0.683)
    );
    assert!(
        (two - 0.954).abs() <= slack(0.954),
        "{:.1} % within 2σ (expected 95.4 ± {:.1} %)",
        100.0 * two,
        100.0 * slack(0.954)
    );

    let bare = z_scores(false, 30);
    let two_bare = within(&bare, 2.0);
    eprintln!(
        "intrinsics taken as exact: {:.1} % within 2σ",
        100.0 * two_bare
    );
    assert!(two_bare < 0.5, "without the calibration's covariance the σ should not cover the error ({:.1} % within 2σ): the test would not see the bug", 100.0 * two_bare);
}

#[test]
fn a_calibration_covariance_of_the_wrong_size_leaves_no_pose() {
    // the pose is not reported rather than reported too sure
    let cam = common::test_camera();
    let pose = common::look_at_target([0.054, 0.042], 0.4, [0.1, -0.1, 0.2], [0.0, 0.0]);
    let rendered = render_view(
        &cam,
        &pose,
        &common::checkerboard_target(),
        &RenderSettings::default(),
    )
    .unwrap();
    let family = TargetFamily::parse("checkerboard", Some((8, 6)), Some(0.012)).unwrap();
    let wrong = DMatrix::<f64>::identity(4, 4);
    let inputs = PoseInputs {
        camera: &cam,
        marker_side: None,
        fallback_sigma_px: 0.1,
        intrinsics_covariance: Some(&wrong),
    };
    let found = detect_targets(
        &rendered.image,
        &family,
        &DetectorParams::default(),
        Some(inputs),
    )
    .unwrap();
    assert_eq!(found.len(), 1);
    assert!(found[0].pose.is_none());
}
