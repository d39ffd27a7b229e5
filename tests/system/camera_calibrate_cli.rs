//! `metrocell camera calibrate` end to end from image files on disk: twelve PNG views of a 9×6
//! checkerboard (25 mm squares) made by `tests/py/opencv_render.py` (OpenCV's camera model,
//! inverse warping, 4×4 supersampling, blur 0.7 px, noise 1 grey level; not metrocell's
//! renderer) with a known camera; the CLI must find every board and recover every intrinsic
//! parameter within 3 of the standard uncertainties it prints, and write the same values as
//! ROS camera_info YAML. A second test shows where the +2.5 σ of fx and fy comes from: a
//! systematic corner error under lens distortion (see its doc).
//!
//! Run: `cargo build --workspace --bins && METROCELL_PYTHON=.venv/bin/python cargo test -p metrocell-system-tests --test camera_calibrate_cli -- --nocapture`

use std::time::Duration;

use nalgebra::{Rotation3, Vector3};
use serde_json::json;
use system_tests::{bin, piped, python, run, workspace_root};

#[test]
fn calibrate_from_png_files_recovers_the_camera_within_its_uncertainty() {
    let tmp = std::env::temp_dir().join(format!("metrocell-calibrate-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let views_dir = render_twelve_views(&tmp, "views", true, 1.0);
    // The truth: Brown–Conrady k1 k2 p1 p2 k3 (OpenCV order).
    let truth = [
        ("fx", 700.0),
        ("fy", 705.0),
        ("cx", 405.3),
        ("cy", 296.8),
        ("k1", -0.12),
        ("k2", 0.05),
        ("p1", 0.0),
        ("p2", 0.0),
        ("k3", 0.0),
    ];
    let yaml = tmp.join("camera_info.yaml");
    let out = calibrate(&views_dir, &yaml);
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "calibrate failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        !stdout.contains("rejected"),
        "a view was rejected:\n{stdout}"
    );
    assert!(
        stdout.contains("(12 views, 648 corners;"),
        "every view and corner used:\n{stdout}"
    );
    // "  fx =     700.012345 ± 0.123456"
    let mut estimated = Vec::new();
    for (name, true_value) in truth {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} =")))
            .unwrap_or_else(|| panic!("no {name} in:\n{stdout}"));
        let (v, s) = line.split_once('=').unwrap().1.split_once('±').unwrap();
        let (v, s): (f64, f64) = (v.trim().parse().unwrap(), s.trim().parse().unwrap());
        let z = (v - true_value) / s;
        println!("{name}: {v} ± {s}, truth {true_value}, error {:+.2} σ", z);
        assert!(
            s > 0.0 && z.abs() <= 3.0,
            "{name} = {v} ± {s}: truth {true_value} is {z:.1} σ away"
        );
        estimated.push(v);
    }
    // Meaningful uncertainties: the focal length to 0.1 %, the principal point to 1 px.
    let sd = |name: &str| {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} =")))
            .unwrap();
        line.split_once('±')
            .unwrap()
            .1
            .trim()
            .parse::<f64>()
            .unwrap()
    };
    assert!(
        sd("fx") < 0.7 && sd("fy") < 0.7 && sd("cx") < 1.0 && sd("cy") < 1.0,
        "uncertainties too wide to test anything:\n{stdout}"
    );
    // The YAML holds the printed values (camera_matrix row-major, distortion k1 k2 p1 p2 k3).
    let text = std::fs::read_to_string(&yaml).unwrap();
    let info: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let k: Vec<f64> = info["camera_matrix"]["data"]
        .as_sequence()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let d: Vec<f64> = info["distortion_coefficients"]["data"]
        .as_sequence()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (file, printed) in [k[0], k[4], k[2], k[5], d[0], d[1], d[2], d[3], d[4]]
        .iter()
        .zip(&estimated)
    {
        // printed with 6 decimals
        assert!(
            (file - printed).abs() <= 5.1e-7,
            "YAML {file} vs printed {printed}:\n{text}"
        );
    }
    assert_eq!(
        (info["image_width"].as_u64(), info["image_height"].as_u64()),
        (Some(800), Some(600))
    );
    let _ = std::fs::remove_dir_all(&tmp);
}

/// Twelve PNG views of a 9×6 checkerboard (25 mm squares) made by `tests/py/opencv_render.py`
/// into `tmp/name`: fx 700, fy 705, cx 405.3, cy 296.8 on an 800×600 sensor, with the lens
/// distortion k1 −0.12, k2 0.05 or without, blur 0.7 px, `noise` grey levels. Board centres over
/// a 4×3 grid of the image (the whole board inside the frame), 0.40–0.51 m away, each tilted
/// differently.
fn render_twelve_views(
    tmp: &std::path::Path,
    name: &str,
    distortion: bool,
    noise: f64,
) -> std::path::PathBuf {
    let views_dir = tmp.join(name);
    std::fs::create_dir_all(&views_dir).unwrap();
    let (cols, rows, square) = (9usize, 6usize, 0.025);
    let dist = if distortion {
        [-0.12, 0.05, 0.0, 0.0, 0.0]
    } else {
        [0.0; 5]
    };
    let camera = json!({"width": 800, "height": 600, "fx": 700.0, "fy": 705.0, "cx": 405.3, "cy": 296.8, "dist": dist});
    let centre = Vector3::new(
        (cols - 1) as f64 * square / 2.0,
        (rows - 1) as f64 * square / 2.0,
        0.0,
    );
    let views: Vec<_> = (0..12)
        .map(|k| {
            let (i, j) = (k % 4, k / 4);
            let axis = Vector3::new(0.35 * ((k as f64) * 1.3).sin(), 0.35 * ((k as f64) * 0.7).cos(), 0.15 * ((k as f64) * 2.1).sin());
            let at = Vector3::new(-0.09 + 0.06 * i as f64, -0.06 + 0.06 * j as f64, 0.40 + 0.01 * k as f64);
            let t = at - Rotation3::from_scaled_axis(axis) * centre;
            json!({"rvec": [axis.x, axis.y, axis.z], "tvec": [t.x, t.y, t.z], "blur": 0.7, "noise": noise, "seed": k})
        })
        .collect();
    let request = json!({"target": "checkerboard", "cols": cols, "rows": rows, "square": square, "out_dir": views_dir, "supersample": 4, "camera": camera, "views": views});
    let req_path = tmp.join(format!("{name}.json"));
    std::fs::write(&req_path, request.to_string()).unwrap();
    let rendered = run(
        piped(python())
            .arg(workspace_root().join("tests/py/opencv_render.py"))
            .arg(&req_path),
        Duration::from_secs(900),
    );
    assert!(
        rendered.status.success(),
        "opencv_render.py: {}",
        String::from_utf8_lossy(&rendered.stderr)
    );
    views_dir
}

/// `metrocell camera calibrate` on every PNG in `views_dir`, writing `yaml`.
fn calibrate(views_dir: &std::path::Path, yaml: &std::path::Path) -> std::process::Output {
    run(
        piped(bin("metrocell"))
            .args(["camera", "calibrate", "--images"])
            .arg(views_dir.join("*.png"))
            .args(["--board", "9x6", "--square", "25mm", "-o"])
            .arg(yaml),
        Duration::from_secs(300),
    )
}

/// The twelve views with `noise`, with or without the lens distortion, calibrated by the CLI:
/// (fx − 700, fy − 705, σ_fx, σ_fy) in px.
fn focal_errors(
    tmp: &std::path::Path,
    name: &str,
    distortion: bool,
    noise: f64,
) -> (f64, f64, f64, f64) {
    let views_dir = render_twelve_views(tmp, name, distortion, noise);
    let out = calibrate(&views_dir, &tmp.join(format!("{name}.yaml")));
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success() && stdout.contains("(12 views, 648 corners;"),
        "{name}: calibrate failed or dropped corners:\n{stdout}"
    );
    let value = |n: &str| -> (f64, f64) {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{n} =")))
            .unwrap_or_else(|| panic!("no {n} in:\n{stdout}"));
        let (v, s) = line.split_once('=').unwrap().1.split_once('±').unwrap();
        (v.trim().parse().unwrap(), s.trim().parse().unwrap())
    };
    let ((fx, sx), (fy, sy)) = (value("fx"), value("fy"));
    eprintln!(
        "{name}: fx − truth {:+.3} px ({:+.2} σ), fy − truth {:+.3} px ({:+.2} σ)",
        fx - 700.0,
        (fx - 700.0) / sx,
        fy - 705.0,
        (fy - 705.0) / sy
    );
    (fx - 700.0, fy - 705.0, sx, sy)
}

/// Why fx and fy come out ≈ +2.5 σ in the test above (issue 15): not image noise, and not a
/// wrong σ scale for noise — a systematic corner error that lens distortion causes. The
/// checkerboard corner detector (like OpenCV's cornerSubPix) locates a saddle assuming straight
/// edges through it; distortion bends the edges, so each corner moves by a few hundredths of a
/// pixel, in a pattern that grows with the distance from the image centre. The calibration takes
/// that pattern for a slightly longer focal length (+0.25 px of 700, 0.035 %, measured); the
/// stated σ comes from the residuals as if they were independent noise, so it does not cover it.
/// Asserted, on the same twelve views rendered without noise:
/// * with the lens distortion the focal lengths are off by 0.1–0.5 px, both the same way
///   (without any image noise, so the error is systematic);
/// * without the distortion both are within 0.1 px and within 1 σ of the truth.
#[test]
fn focal_length_bias_comes_from_distorted_edges_not_from_noise() {
    let tmp = std::env::temp_dir().join(format!("metrocell-calibrate-bias-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let (ex, ey, _, _) = focal_errors(&tmp, "distorted_noise_free", true, 0.0);
    assert!((0.1..=0.5).contains(&ex.abs()) && (0.1..=0.5).contains(&ey.abs()) && ex.signum() == ey.signum(), "with distortion, no noise: fx {ex:+.3} px, fy {ey:+.3} px (expected the same systematic 0.1–0.5 px in both)");
    let (ex, ey, sx, sy) = focal_errors(&tmp, "undistorted_noise_free", false, 0.0);
    assert!(ex.abs() < 0.1 && ey.abs() < 0.1 && ex.abs() <= sx && ey.abs() <= sy, "without distortion: fx {ex:+.3} ± {sx:.3} px, fy {ey:+.3} ± {sy:.3} px (expected within 0.1 px and 1 σ)");
    let _ = std::fs::remove_dir_all(&tmp);
}
