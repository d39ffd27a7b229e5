//! Speed of `detect_markers` against OpenCV's ArucoDetector on the same frames, in the same run.
//!
//!   METROCELL_PYTHON=/path/to/venv/python cargo run --release -p metrocell-vision --example aruco_benchmark
//!
//! Frames: 1920×1080 and 3840×2160 renders of a slightly tilted plane carrying 1 or 20
//! DICT_6X6_250 markers (blur 0.8 px, noise 2 grey levels). Prints median times and the ratio
//! ours / OpenCV, both single-threaded and both on all cores. Runs alternate one of ours, one of
//! OpenCV's (a persistent Python process, tests/py/bench_opencv.py). REPEATS=n (default 9).

use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};
use metrocell_vision::{
    render_view, CameraModel, Distortion, PlanarTarget, RenderSettings, TargetItem,
};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
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
    let repeats: usize = std::env::var("REPEATS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(9);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut cases = Vec::new();
    for (w, h) in [(1920u32, 1080u32), (3840, 2160)] {
        for n in [1usize, 20] {
            // 0.6 m × 0.34 m plane at 1 m; f chosen so it fills the frame width.
            let f = w as f64 * 1.0 / 0.7;
            let cam = CameraModel::new(
                w,
                h,
                f,
                f,
                (w as f64 - 1.0) / 2.0,
                (h as f64 - 1.0) / 2.0,
                Distortion::none(),
            )
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
            cases.push((w, h, n, path, img));
        }
    }
    // One OpenCV process answers one timed detection per request, so each of our runs is
    // followed by one of OpenCV's on the same frame: load from other processes hits both alike.
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/py/bench_opencv.py");
    let mut cv = Command::new(python())
        .arg(script)
        .args(["DICT_6X6_250", "subpix"])
        .args(cases.iter().map(|c| c.3.clone()))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("run python");
    let mut cv_in = cv.stdin.take().unwrap();
    let mut cv_out = BufReader::new(cv.stdout.take().unwrap());
    let mut cv_detect = |threads: i32, k: usize| -> (f64, usize) {
        writeln!(cv_in, "{threads} {k}").unwrap();
        let mut line = String::new();
        cv_out.read_line(&mut line).unwrap();
        let mut it = line.split_whitespace();
        match (
            it.next().and_then(|v| v.parse().ok()),
            it.next().and_then(|v| v.parse().ok()),
        ) {
            (Some(t), Some(n)) => (t, n),
            _ => panic!("bench_opencv.py replied {line:?} (see its stderr above)"),
        }
    };
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!("ArUco detection, median of {repeats} interleaved runs (ours: edge-fit refinement; OpenCV: CORNER_REFINE_SUBPIX)");
    println!("single-threaded (ours threads=1, cv2.setNumThreads(1)) | all {cores} cores (ours threads=0, cv2.setNumThreads(-1) = all)");
    println!(
        "{:>10} {:>7} {:>5} {:>5} | {:>8} {:>8} {:>6} | {:>8} {:>8} {:>6}",
        "frame", "markers", "ours", "cv", "ours ms", "cv ms", "ratio", "ours ms", "cv ms", "ratio"
    );
    for (k, (w, h, n, _, img)) in cases.iter().enumerate() {
        let mut row = Vec::new();
        let (mut found, mut cv_found) = (0, 0);
        for (threads, cv_threads) in [(1usize, 1i32), (0, -1)] {
            let params = DetectorParams {
                threads,
                ..Default::default()
            };
            // warm-up
            let _ = detect_markers(img, &dict, &params).unwrap();
            let _ = cv_detect(cv_threads, k);
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            for _ in 0..repeats {
                let t0 = Instant::now();
                found = detect_markers(img, &dict, &params).unwrap().len();
                ours.push(t0.elapsed().as_secs_f64());
                let (t, nf) = cv_detect(cv_threads, k);
                theirs.push(t);
                cv_found = nf;
            }
            row.push((median(ours), median(theirs)));
        }
        println!(
            "{:>10} {:>7} {:>5} {:>5} | {:>8.1} {:>8.1} {:>6.2} | {:>8.1} {:>8.1} {:>6.2}",
            format!("{w}x{h}"),
            n,
            found,
            cv_found,
            row[0].0 * 1e3,
            row[0].1 * 1e3,
            row[0].0 / row[0].1,
            row[1].0 * 1e3,
            row[1].1 * 1e3,
            row[1].0 / row[1].1
        );
    }
    drop(cv_in);
    let _ = cv.wait();
    println!("ratio = ours / OpenCV time (< 1 means faster than OpenCV)");
}
