//! Issue 32, item 11: checkerboard views drawn by OpenCV (tests/py/opencv_render.py: OpenCV's
//! camera model, area-sampled, not metrocell's renderer) that OpenCV's findChessboardCorners
//! finds and metrocell did not:
//! * a sharp (unblurred) board whose edges run almost along the pixel rows: the crossing-edges
//!   fit let the edge spread fall below a pixel's own (1/√12 px), wandered, and its covariance
//!   was singular — "corner … did not converge";
//! * two strongly foreshortened boards: the lattice grew from a diagonal neighbour, in sheared
//!   coordinates (a 9×6 board spanning 14×6), and was not taken for a board.
//!
//! All three must now be found with every corner within 0.1 px of OpenCV's projection of the
//! board; and when a board is not found, the reason says what to check.

mod common;

use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::checkerboard::detect_checkerboard;
use metrocell_vision::{detect_targets_explained, TargetFamily};
use nalgebra::Point2;
use serde_json::json;

/// (name, rvec, tvec, blur px, noise grey levels, noise seed): three of 40 random views drawn
/// for the issue, where metrocell failed and OpenCV did not.
type View = (&'static str, [f64; 3], [f64; 3], f64, f64, u64);

const VIEWS: [View; 4] = [
    (
        "sharp_axis_aligned",
        [
            -0.17742373279939552,
            -0.6758742508507913,
            -1.5223137705805014,
        ],
        [
            -0.06480643876377329,
            0.05282651897920952,
            0.7034484716735545,
        ],
        0.0,
        2.0,
        33,
    ),
    (
        "foreshortened",
        [-1.1812779642481457, -1.9508630492979229, -1.314657690071884],
        [
            0.025769071967748025,
            -0.0988956743262775,
            0.5315142125487697,
        ],
        0.0,
        0.5,
        21,
    ),
    (
        "foreshortened_blurred",
        [
            -1.0398794970096445,
            -0.4704780442895363,
            -0.6851109274890073,
        ],
        [
            -0.03299478232032384,
            0.04672653738562756,
            0.6449300155814147,
        ],
        1.5,
        2.0,
        31,
    ),
    // the first view moved 40 cm to the right: the board is cut by the image's edge
    (
        "cut_by_the_edge",
        [
            -0.17742373279939552,
            -0.6758742508507913,
            -1.5223137705805014,
        ],
        [0.33519356123622671, 0.05282651897920952, 0.7034484716735545],
        0.0,
        2.0,
        33,
    ),
];

#[test]
fn boards_opencv_finds_are_found_and_a_missing_one_says_why() {
    let dir = common::temp_dir("checkerboard-opencv-views");
    let camera = json!({"width": 800, "height": 600, "fx": 700.0, "fy": 704.9, "cx": 400.3, "cy": 296.8, "dist": [-0.12, 0.05, 0.0, 0.0, 0.0]});
    let views: Vec<_> = VIEWS.iter().map(|(_, r, t, blur, noise, seed)| json!({"rvec": r, "tvec": t, "blur": blur, "noise": noise, "seed": seed})).collect();
    let request = json!({"target": "checkerboard", "cols": 9, "rows": 6, "square": 0.025, "out_dir": dir, "supersample": 3, "camera": camera, "views": views});
    let request_path = dir.join("request.json");
    std::fs::write(&request_path, request.to_string()).unwrap();
    let renderer =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/py/opencv_render.py");
    let out = std::process::Command::new(common::python())
        .arg(&renderer)
        .arg(&request_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "opencv_render.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rendered: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let paths: Vec<String> = rendered
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["path"].as_str().unwrap().to_string())
        .collect();
    let mut args = vec!["chessboard", "9", "6"];
    args.extend(paths.iter().map(String::as_str));
    let opencv = common::run_py("chessboard_reference.py", &args);

    for (k, (name, ..)) in VIEWS.iter().enumerate().take(3) {
        assert!(
            !opencv[k]["subpix"].is_null(),
            "{name}: the premise is that OpenCV's findChessboardCorners finds it"
        );
        let truth: Vec<Point2<f64>> = rendered[k]["corners"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| Point2::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
            .collect();
        let img = image::open(&paths[k]).unwrap().to_luma8();
        let board = detect_checkerboard(&img, 9, 6).unwrap_or_else(|e| panic!("{name}: {e}"));
        let worst_of = |found: &[Point2<f64>]| {
            found
                .iter()
                .map(|c| {
                    truth
                        .iter()
                        .map(|t| (t - c).norm())
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0f64, f64::max)
        };
        let ours: Vec<Point2<f64>> = board.corners.iter().map(|c| c.position).collect();
        let theirs: Vec<Point2<f64>> = opencv[k]["subpix"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| Point2::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
            .collect();
        let (worst, cv_worst) = (worst_of(&ours), worst_of(&theirs));
        eprintln!("{name}: 54 corners, worst {worst:.3} px from OpenCV's projection (cornerSubPix: {cv_worst:.3} px)");
        assert!(
            worst < 0.12 && worst <= cv_worst,
            "{name}: a corner {worst:.3} px from the truth (cornerSubPix {cv_worst:.3})"
        );
    }

    // not found: the reason says what to check
    let family = TargetFamily::parse("checkerboard", Some((9, 6)), Some(0.025)).unwrap();
    let img = image::open(&paths[3]).unwrap().to_luma8();
    let d = detect_targets_explained(&img, &family, &DetectorParams::default(), None).unwrap();
    let why = d.not_found.expect("a reason when no board is found");
    assert!(d.targets.is_empty());
    assert!(
        why.starts_with("only ")
            && why.contains("a 9×6 board has 54")
            && why.contains("whole board in the frame"),
        "{why}"
    );
    // a --board that is not the board's: the lattice it has is named
    let img = image::open(&paths[0]).unwrap().to_luma8();
    let why = |cols, rows| {
        let wrong = TargetFamily::parse("checkerboard", Some((cols, rows)), Some(0.025)).unwrap();
        detect_targets_explained(&img, &wrong, &DetectorParams::default(), None)
            .unwrap()
            .not_found
            .unwrap()
    };
    let (larger, smaller) = (why(10, 6), why(8, 6));
    assert!(
        larger.starts_with("only 54 points")
            && larger
                .contains("a 10×6 board has 60; the largest lattice of them spans 9×6 (54 points)"),
        "{larger}"
    );
    assert!(
        smaller.contains("no 8×6 lattice")
            && smaller.contains("the largest lattice of them spans 9×6 (54 points)")
            && smaller.contains("check --board"),
        "{smaller}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
