//! Checkerboard inner corners against the rendered truth and OpenCV's findChessboardCornersSB.
mod common;

use metrocell_vision::checkerboard::detect_checkerboard;
use metrocell_vision::{render_view, RenderSettings};
use nalgebra::Point2;

/// Three poses × three imaging conditions: all 8×6 corners found; per condition our RMS vs
/// truth is no worse than findChessboardCornersSB's (CALIB_CB_ACCURACY) nor cornerSubPix's, and
/// < 0.05 px on clean renders.
#[test]
fn corners_match_truth_at_least_as_well_as_opencv_sb() {
    let dir = common::temp_dir("checkerboard-accuracy");
    let cam = common::test_camera();
    let target = common::checkerboard_target();
    let poses = [
        common::look_at_target([0.054, 0.042], 0.45, [0.0, 0.0, 0.05], [0.0, 0.0]),
        common::look_at_target([0.054, 0.042], 0.40, [0.35, -0.2, 0.6], [0.02, -0.01]),
        common::look_at_target([0.054, 0.042], 0.50, [-0.4, 0.3, -0.3], [-0.06, 0.04]),
    ];
    let base = RenderSettings::default();
    let conditions = [
        ("clean", base),
        (
            "blur1",
            RenderSettings {
                blur_sigma_px: 1.0,
                ..base
            },
        ),
        (
            "blur1.2+noise3+gradient",
            RenderSettings {
                blur_sigma_px: 1.2,
                noise_sigma: 3.0,
                gradient: [0.4, 0.2],
                seed: 5,
                ..base
            },
        ),
    ];
    for (name, settings) in conditions {
        let mut paths = Vec::new();
        let mut truths = Vec::new();
        let mut ours_sq = Vec::new();
        for (k, pose) in poses.iter().enumerate() {
            let view = render_view(&cam, pose, &target, &settings).unwrap();
            let p = dir.join(format!("{name}_pose{k}.png"));
            common::save_png(&view.image, &p);
            let img = image::open(&p).unwrap().to_luma8();
            let board =
                detect_checkerboard(&img, 8, 6).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let found: Vec<Point2<f64>> = board.corners.iter().map(|c| c.position).collect();
            let truth = &view.checkerboard_corners[0];
            ours_sq.push(common::nearest_rms(truth, &found).powi(2));
            // Ordering documented for near-frontal boards: same as the renderer's (top-left first).
            if k == 0 {
                for (f, t) in found.iter().zip(truth) {
                    assert!(
                        (f - t).norm() < 0.2,
                        "{name} pose 0: order differs from truth"
                    );
                }
            }
            paths.push(p.to_str().unwrap().to_string());
            truths.push(truth.clone());
        }
        let mut args = vec!["chessboard", "8", "6"];
        args.extend(paths.iter().map(|s| s.as_str()));
        let cv = common::run_py("chessboard_reference.py", &args);
        let cv_sq: Vec<f64> = truths
            .iter()
            .enumerate()
            .map(|(k, t)| {
                common::nearest_rms(
                    t,
                    &common::parse_points(&cv[k]["sb"]).expect("SB found the board"),
                )
                .powi(2)
            })
            .collect();
        let sub_sq: Vec<f64> = truths
            .iter()
            .enumerate()
            .map(|(k, t)| {
                common::nearest_rms(
                    t,
                    &common::parse_points(&cv[k]["subpix"]).expect("cornerSubPix board"),
                )
                .powi(2)
            })
            .collect();
        // Mean of per-image mean squares (each image has 48 corners).
        let (r_ours, r_cv, r_sub) = (
            common::rms(&ours_sq),
            common::rms(&cv_sq),
            common::rms(&sub_sq),
        );
        eprintln!(
            "{name:>24}: checkerboard corner RMS vs truth: ours {r_ours:.4} px, OpenCV SB {r_cv:.4} px, \
             findChessboardCorners+cornerSubPix {r_sub:.4} px"
        );
        assert!(
            r_ours <= r_cv,
            "{name}: ours {r_ours:.4} px vs OpenCV SB {r_cv:.4} px"
        );
        assert!(
            r_ours <= r_sub,
            "{name}: ours {r_ours:.4} px vs OpenCV cornerSubPix {r_sub:.4} px"
        );
        if name == "clean" {
            assert!(r_ours < 0.05, "clean: {r_ours:.4} px");
        }
    }
}
