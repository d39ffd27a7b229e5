//! Speed of `detect_markers` against OpenCV's ArucoDetector on the same frames, in the same run.
//!
//!   METROCELL_PYTHON=/path/to/venv/python cargo run --release -p metrocell-vision --example aruco_benchmark
//!
//! Frames: 1920×1080 and 3840×2160 renders of a slightly tilted plane carrying 1 or 20
//! DICT_6X6_250 markers (blur 0.8 px, noise 2 grey levels). Prints median times and the ratio
//! ours / OpenCV, both single-threaded and both on all cores.

use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};
use metrocell_vision::{render_view, CameraModel, Distortion, PlanarTarget, RenderSettings, TargetItem};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    if venv.exists() {
        return venv;
    }
    eprintln!(
        "set METROCELL_PYTHON or run tests/run to create {}",
        venv.display()
    );
    std::process::exit(2);
}

fn main() {
    let dict = Dictionary::predefined("DICT_6X6_250").unwrap();
    let dir = std::env::temp_dir().join(format!("metrocell-vision-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let repeats = 7;
    let mut cases = Vec::new();
    for (w, h) in [(1920u32, 1080u32), (3840, 2160)] {
        for n in [1usize, 20] {
            // 0.6 m × 0.34 m plane at 1 m; f chosen so it fills the frame width.
            let f = w as f64 * 1.0 / 0.7;
            let cam =
                CameraModel::new(w, h, f, f, (w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0, Distortion::none())
                    .unwrap();
            let (cols, rows) = if n == 1 { (1, 1) } else { (5, 4) };
            let side = 0.06;
            let items = (0..n)
                .map(|k| TargetItem::Marker {
                    dictionary: dict,
                    id: k * 7 % 250,
                    top_left: [(k % cols) as f64 * 0.12, (k / cols) as f64 * 0.075],
                    side,
                    border_bits: 1,
                })
                .collect();
            let (cx, cy) = (
                (cols as f64 - 1.0) * 0.06 + side / 2.0,
                (rows as f64 - 1.0) * 0.0375 + side / 2.0,
            );
            let rot = UnitQuaternion::from_euler_angles(0.15, -0.1, 0.05);
            let t = Vector3::new(0.0, 0.0, 1.0) - rot * Vector3::new(cx, cy, 0.0);
            let pose = Isometry3::from_parts(Translation3::from(t), rot);
            let settings = RenderSettings {
                supersampling: 8,
                blur_sigma_px: 0.8,
                noise_sigma: 2.0,
                ..Default::default()
            };
            let view = render_view(&cam, &pose, &PlanarTarget { items }, &settings).unwrap();
            let path = dir.join(format!("frame_{w}x{h}_{n}.png"));
            view.image.save(&path).unwrap();
            let img = image::open(&path).unwrap().to_luma8();
            let mut medians = [0.0; 2];
            let mut found = 0;
            for (slot, threads) in [1usize, 0].into_iter().enumerate() {
                let params = DetectorParams {
                    threads,
                    ..Default::default()
                };
                let _ = detect_markers(&img, &dict, &params).unwrap(); // warm-up
                let mut times = Vec::new();
                for _ in 0..repeats {
                    let t0 = Instant::now();
                    found = detect_markers(&img, &dict, &params).unwrap().len();
                    times.push(t0.elapsed().as_secs_f64());
                }
                times.sort_by(f64::total_cmp);
                medians[slot] = times[repeats / 2];
            }
            cases.push((w, h, n, path, medians, found));
        }
    }
    let paths: Vec<String> = cases
        .iter()
        .map(|c| c.3.to_str().unwrap().to_string())
        .collect();
    let run_cv = |threads: &str| -> serde_json::Value {
        let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/py/bench_opencv.py");
        let out = Command::new(python())
            .arg(script)
            .args(["DICT_6X6_250", "subpix", threads, &repeats.to_string()])
            .args(&paths)
            .output()
            .expect("run python");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let cv1 = run_cv("1");
    let cvn = run_cv("-1");
    println!("ArUco detection, median of {repeats} runs (ours: edge-fit refinement; OpenCV: CORNER_REFINE_SUBPIX)");
    println!("single-threaded (ours threads=1, cv2.setNumThreads(1)) | all cores (ours threads=0, OpenCV default)");
    println!(
        "{:>10} {:>7} {:>5} {:>5} | {:>8} {:>8} {:>6} | {:>8} {:>8} {:>6}",
        "frame", "markers", "ours", "cv", "ours ms", "cv ms", "ratio", "ours ms", "cv ms", "ratio"
    );
    for (k, (w, h, n, _, t, found)) in cases.iter().enumerate() {
        let t1 = cv1[k]["median_s"].as_f64().unwrap();
        let tn = cvn[k]["median_s"].as_f64().unwrap();
        println!(
            "{:>10} {:>7} {:>5} {:>5} | {:>8.1} {:>8.1} {:>6.2} | {:>8.1} {:>8.1} {:>6.2}",
            format!("{w}x{h}"),
            n,
            found,
            cv1[k]["found"].as_u64().unwrap_or(0),
            t[0] * 1e3,
            t1 * 1e3,
            t[0] / t1,
            t[1] * 1e3,
            tn * 1e3,
            t[1] / tn
        );
    }
    println!("ratio = ours / OpenCV time (< 1 means faster than OpenCV)");
}
