//! Zhang calibration against cv2.calibrateCamera and cv2.fisheye.calibrate on the same corner sets.

mod common;
use common::*;
use metrocell_camera_model::{calibrate, CalibrationFlags, LensModel};
use serde_json::json;

fn compare(model: LensModel, seed: u64, sigma: f64) {
    compare_with_flags(
        model,
        seed,
        sigma,
        CalibrationFlags {
            outlier_view_ratio: None,
            ..Default::default()
        },
        &[],
    );
}

fn compare_with_flags(
    model: LensModel,
    seed: u64,
    sigma: f64,
    flags: CalibrationFlags,
    cv_flags: &[&str],
) {
    let truth = match model {
        LensModel::BrownConrady => pinhole_truth(),
        LensModel::Fisheye => fisheye_truth(),
    };
    let dist = match model {
        LensModel::BrownConrady => (0.35, 0.7),
        LensModel::Fisheye => (0.2, 0.45),
    };
    let (views, _) = synthetic_views(&truth, 20, sigma, seed, dist);
    let ours = calibrate(&views, (truth.width, truth.height), model, &flags).unwrap();
    let cv = opencv(
        &json!({"op": "calibrate", "model": if model == LensModel::Fisheye { "fisheye" } else { "plumb_bob" },
        "views": views_json(&views), "image_size": [truth.width, truth.height], "flags": cv_flags}),
    );
    let c = ours.camera;
    let theirs = [f(&cv["fx"]), f(&cv["fy"]), f(&cv["cx"]), f(&cv["cy"])];
    let mine = [c.fx, c.fy, c.cx, c.cy];
    println!("{model:?} {cv_flags:?} seed {seed} σ={sigma}: ours fx {:.4} fy {:.4} cx {:.4} cy {:.4} rms {:.5} | OpenCV {:.4} {:.4} {:.4} {:.4} rms {:.5} | truth {:.1} {:.1} {:.1} {:.1}",
        mine[0], mine[1], mine[2], mine[3], ours.rms_px, theirs[0], theirs[1], theirs[2], theirs[3], f(&cv["rms"]), truth.fx, truth.fy, truth.cx, truth.cy);
    println!(
        "   distortion ours {:?}\n   distortion cv   {:?}",
        c.distortion.coefficients(),
        cv["coeffs"]
    );
    for i in 0..4 {
        let rel = (mine[i] - theirs[i]).abs() / theirs[i].abs();
        assert!(
            rel < 1e-3,
            "{model:?} intrinsic {i}: ours {} vs OpenCV {} (rel {rel:.2e})",
            mine[i],
            theirs[i]
        );
    }
    let rms_rel = (ours.rms_px - f(&cv["rms"])).abs() / f(&cv["rms"]);
    assert!(
        rms_rel < 0.05,
        "{model:?} RMS ours {} vs OpenCV {}",
        ours.rms_px,
        f(&cv["rms"])
    );
    if model == LensModel::BrownConrady {
        // Same σ² = Σr²/(2N − P) and (JᵀJ)⁻¹ as OpenCV 5's stdDeviationsIntrinsics: ratio 1.
        let expect = 1.0;
        let std_cv = cv["std_intrinsics"].as_array().unwrap();
        #[allow(clippy::needless_range_loop)]
        for i in 0..4 {
            if f(&std_cv[i]) == 0.0 && i < 2 && cv_flags.contains(&"CALIB_FIX_ASPECT_RATIO") {
                // OpenCV reports 0 for the tied focal length; ours propagates the free one's
                // uncertainty through the fixed ratio.
                let (fi, fo) = if i == 0 { (c.fx, c.fy) } else { (c.fy, c.fx) };
                let expect = ours.param_std[1 - i] * fi / fo;
                println!(
                    "   std param {i}: tied, ours {:.4} = {:.4}·{fi:.3}/{fo:.3}",
                    ours.param_std[i],
                    ours.param_std[1 - i]
                );
                assert!(
                    (ours.param_std[i] - expect).abs() < 1e-9 * expect,
                    "tied focal std {} vs {expect}",
                    ours.param_std[i]
                );
                continue;
            }
            if f(&std_cv[i]) == 0.0 {
                assert_eq!(
                    ours.param_std[i], 0.0,
                    "fixed parameter {i} must report zero uncertainty"
                );
                continue;
            }
            let ratio = ours.param_std[i] / f(&std_cv[i]);
            println!(
                "   std param {i}: ours {:.4} OpenCV {:.4} ratio {ratio:.4} (expected {expect:.4})",
                ours.param_std[i],
                f(&std_cv[i])
            );
            assert!(
                (ratio - expect).abs() < 0.01 * expect,
                "std ratio {ratio} vs expected {expect}"
            );
        }
        let pv = cv["per_view_rms"].as_array().unwrap();
        for (k, v) in ours.views.iter().enumerate() {
            assert!(
                (v.rms_px - f(&pv[k])).abs() < 0.01 * f(&pv[k]),
                "view {k} RMS {} vs OpenCV {}",
                v.rms_px,
                f(&pv[k])
            );
        }
    }
}

#[test]
fn brown_conrady_matches_opencv_calibrate_camera() {
    for (seed, sigma) in [(1u64, 0.1), (2, 0.2), (3, 0.3)] {
        compare(LensModel::BrownConrady, seed, sigma);
    }
}

#[test]
fn fisheye_matches_opencv_fisheye_calibrate() {
    for (seed, sigma) in [(4u64, 0.1), (5, 0.3)] {
        compare(LensModel::Fisheye, seed, sigma);
    }
}

#[test]
fn calibration_flags_match_opencv() {
    let flags = CalibrationFlags {
        outlier_view_ratio: None,
        fix_principal_point: true,
        zero_tangential: true,
        fixed_distortion: vec![4],
        ..Default::default()
    };
    compare_with_flags(
        LensModel::BrownConrady,
        7,
        0.2,
        flags,
        &[
            "CALIB_FIX_PRINCIPAL_POINT",
            "CALIB_ZERO_TANGENT_DIST",
            "CALIB_FIX_K3",
        ],
    );
    let flags = CalibrationFlags {
        outlier_view_ratio: None,
        fix_aspect_ratio: true,
        ..Default::default()
    };
    compare_with_flags(
        LensModel::BrownConrady,
        8,
        0.2,
        flags,
        &["CALIB_FIX_ASPECT_RATIO"],
    );
}
