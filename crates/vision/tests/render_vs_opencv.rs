//! The twin renderer's ground truth agrees with what OpenCV measures in its images.
mod common;

use metrocell_vision::{render_view, RenderSettings};

/// Noise-free renders of four markers in four poses: OpenCV (CORNER_REFINE_SUBPIX) finds every
/// marker with the right id, and its corners agree with the rendered ground truth < 0.3 px RMS.
/// cornerSubPix is biased towards the inside of a convex (L-shaped) corner, more so with blur:
/// the measured residual is mostly that inward bias (≈0.06–0.24 px), so the renderer's geometry
/// is checked at saddle points in the next test, where cornerSubPix is unbiased.
#[test]
fn opencv_finds_rendered_markers_at_ground_truth() {
    let dir = common::temp_dir("render-vs-opencv");
    let cam = common::test_camera();
    let target = common::four_marker_target();
    let mut paths = Vec::new();
    let mut truths = Vec::new();
    for (k, pose) in common::test_poses().iter().enumerate() {
        for blur in [0.0, 0.8] {
            let settings = RenderSettings {
                blur_sigma_px: blur,
                ..Default::default()
            };
            let view = render_view(&cam, pose, &target, &settings).unwrap();
            let p = dir.join(format!("pose{k}_blur{blur}.png"));
            common::save_png(&view.image, &p);
            paths.push(p.to_str().unwrap().to_string());
            truths.push(view.markers);
        }
    }
    let mut args = vec!["detect", "DICT_4X4_50", "subpix"];
    args.extend(paths.iter().map(|s| s.as_str()));
    let cv = common::run_py("aruco_reference.py", &args);
    let mut all = Vec::new();
    for (k, truth) in truths.iter().enumerate() {
        let found = common::parse_detections(&cv[k]);
        assert_eq!(
            found.len(),
            4,
            "{}: OpenCV found {:?}",
            paths[k],
            found.iter().map(|f| f.0).collect::<Vec<_>>()
        );
        let sq = common::corner_sq_errors(truth, &found, &paths[k]);
        eprintln!(
            "{}: OpenCV subpix RMS vs truth {:.4} px, mean inward bias {:.4} px",
            paths[k],
            common::rms(&sq),
            common::mean_inward_bias(truth, &found)
        );
        all.extend(sq);
    }
    let rms = common::rms(&all);
    eprintln!(
        "overall OpenCV subpix RMS vs truth: {rms:.4} px over {} corners",
        all.len()
    );
    assert!(
        rms < 0.3,
        "OpenCV corners vs rendered truth: {rms:.4} px RMS"
    );
}

/// Saddle points are where OpenCV's sub-pixel estimators are unbiased, so they check the renderer's
/// geometry (distortion, pose, pixel convention) directly: findChessboardCornersSB and cornerSubPix
/// agree with the rendered truth on noise-free renders: cornerSubPix < 0.1 px RMS (measured
/// 0.02–0.08), findChessboardCornersSB < 0.25 px (measured 0.03–0.19; SB is the coarser of the two).
#[test]
fn opencv_checkerboard_corners_match_rendered_truth() {
    let dir = common::temp_dir("render-checkerboard");
    let cam = common::test_camera();
    let target = common::checkerboard_target();
    let poses = [
        common::look_at_target([0.054, 0.042], 0.45, [0.0, 0.0, 0.05], [0.0, 0.0]),
        common::look_at_target([0.054, 0.042], 0.40, [0.35, -0.2, 0.6], [0.02, -0.01]),
        common::look_at_target([0.054, 0.042], 0.50, [-0.4, 0.3, -0.3], [-0.06, 0.04]),
    ];
    let mut paths = Vec::new();
    let mut truths = Vec::new();
    for (k, pose) in poses.iter().enumerate() {
        for blur in [0.0, 0.8] {
            let settings = RenderSettings {
                blur_sigma_px: blur,
                ..Default::default()
            };
            let view = render_view(&cam, pose, &target, &settings).unwrap();
            let p = dir.join(format!("cb{k}_blur{blur}.png"));
            common::save_png(&view.image, &p);
            paths.push(p.to_str().unwrap().to_string());
            truths.push(view.checkerboard_corners[0].clone());
        }
    }
    let mut args = vec!["chessboard", "8", "6"];
    args.extend(paths.iter().map(|s| s.as_str()));
    let cv = common::run_py("chessboard_reference.py", &args);
    for (k, truth) in truths.iter().enumerate() {
        for method in ["sb", "subpix"] {
            let found = common::parse_points(&cv[k][method])
                .unwrap_or_else(|| panic!("{}: OpenCV {method} found no board", paths[k]));
            assert_eq!(found.len(), 48);
            let rms = common::nearest_rms(truth, &found);
            eprintln!("{}: OpenCV {method} RMS vs truth {rms:.4} px", paths[k]);
            let limit = if method == "sb" { 0.25 } else { 0.1 };
            assert!(rms < limit, "{}: {method} {rms:.4} px", paths[k]);
        }
    }
}
