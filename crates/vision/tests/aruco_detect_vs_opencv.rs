//! ArUco detection accuracy and robustness against ground truth and against OpenCV's detector.
mod common;

use image::GrayImage;
use metrocell_vision::aruco::dictionary::rotate_code;
use metrocell_vision::aruco::{
    detect_markers, generate_marker_image, DetectedMarker, DetectorParams, Dictionary,
};
use metrocell_vision::{render_view, RenderSettings};
use nalgebra::Point2;

/// Squared Mahalanobis distance e'C⁻¹e of each found corner's error under its reported covariance.
fn squared_mahalanobis(
    found: &[DetectedMarker],
    truth: &[metrocell_vision::MarkerTruth],
) -> Vec<f64> {
    let mut out = Vec::new();
    for m in found {
        let t = truth
            .iter()
            .find(|t| t.id == m.id)
            .expect("a found marker is in the scene");
        for k in 0..4 {
            let e = m.corners[k] - t.corners[k];
            let ci = m.corner_covariance[k]
                .try_inverse()
                .expect("finite corner covariance");
            out.push((e.transpose() * ci * e)[(0, 0)]);
        }
    }
    out
}

fn ours(found: &[DetectedMarker]) -> Vec<(usize, [Point2<f64>; 4])> {
    found.iter().map(|m| (m.id, m.corners)).collect()
}

struct Condition {
    name: &'static str,
    settings: RenderSettings,
}

fn conditions() -> Vec<Condition> {
    let base = RenderSettings::default();
    vec![
        Condition {
            name: "clean",
            settings: base,
        },
        Condition {
            name: "blur0.8",
            settings: RenderSettings {
                blur_sigma_px: 0.8,
                ..base
            },
        },
        Condition {
            name: "blur1.5+noise2",
            settings: RenderSettings {
                blur_sigma_px: 1.5,
                noise_sigma: 2.0,
                seed: 7,
                ..base
            },
        },
        Condition {
            name: "blur1+noise5+gradient",
            settings: RenderSettings {
                blur_sigma_px: 1.0,
                noise_sigma: 5.0,
                gradient: [0.5, -0.3],
                seed: 11,
                ..base
            },
        },
    ]
}

/// Four markers, four poses, four imaging conditions. Every marker is found with its id by both
/// detectors; per condition our corner RMS vs ground truth is no worse than OpenCV's
/// (CORNER_REFINE_SUBPIX) on the same PNGs, and < 0.05 px on clean renders.
#[test]
fn corners_match_ground_truth_better_than_opencv() {
    let dir = common::temp_dir("detect-accuracy");
    let cam = common::test_camera();
    let target = common::four_marker_target();
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let params = DetectorParams::default();
    for cond in conditions() {
        let mut paths = Vec::new();
        let mut truths = Vec::new();
        let mut ours_sq = Vec::new();
        let mut mahal = Vec::new();
        for (k, pose) in common::test_poses().iter().enumerate() {
            let view = render_view(&cam, pose, &target, &cond.settings).unwrap();
            let p = dir.join(format!("{}_pose{k}.png", cond.name));
            common::save_png(&view.image, &p);
            // Detect on the decoded PNG, exactly the bytes OpenCV reads.
            let img = image::open(&p).unwrap().to_luma8();
            let found = detect_markers(&img, &dict, &params).unwrap();
            assert_eq!(
                found.len(),
                4,
                "{}: ours found ids {:?}",
                p.display(),
                found.iter().map(|m| m.id).collect::<Vec<_>>()
            );
            ours_sq.extend(common::corner_sq_errors(
                &view.markers,
                &ours(&found),
                &p.display().to_string(),
            ));
            mahal.extend(squared_mahalanobis(&found, &view.markers));
            paths.push(p.to_str().unwrap().to_string());
            truths.push(view.markers);
        }
        let mut args = vec!["detect", "DICT_4X4_50", "subpix"];
        args.extend(paths.iter().map(|s| s.as_str()));
        let cv = common::run_py("aruco_reference.py", &args);
        let mut cv_sq = Vec::new();
        for (k, truth) in truths.iter().enumerate() {
            let found = common::parse_detections(&cv[k]);
            cv_sq.extend(common::corner_sq_errors(truth, &found, &paths[k]));
        }
        // For information: OpenCV's other refinement, line fits to the contour points.
        args[2] = "contour";
        let cvc = common::run_py("aruco_reference.py", &args);
        let mut contour_sq = Vec::new();
        for (k, truth) in truths.iter().enumerate() {
            contour_sq.extend(common::corner_sq_errors(
                truth,
                &common::parse_detections(&cvc[k]),
                &paths[k],
            ));
        }
        eprintln!(
            "{:>24}: OpenCV CORNER_REFINE_CONTOUR RMS vs truth {:.4} px",
            cond.name,
            common::rms(&contour_sq)
        );
        let (r_ours, r_cv) = (common::rms(&ours_sq), common::rms(&cv_sq));
        // E[e'C⁻¹e] = 2 when the covariance is right and errors are noise-dominated.
        let m2 = mahal.iter().sum::<f64>() / mahal.len() as f64;
        eprintln!(
            "{:>24}: corner RMS vs truth: ours {r_ours:.4} px, OpenCV subpix {r_cv:.4} px ({} corners); mean e'C^-1e {m2:.2} (2 if calibrated)",
            cond.name,
            ours_sq.len()
        );
        if cond.settings.noise_sigma > 0.0 {
            // The same scenes with 7 more noise seeds, so the mean rests on 512 corners.
            let mut pooled = mahal.clone();
            for extra in 1..=7u64 {
                let settings = RenderSettings {
                    seed: cond.settings.seed + 1000 * extra,
                    ..cond.settings
                };
                for pose in common::test_poses().iter() {
                    let view = render_view(&cam, pose, &target, &settings).unwrap();
                    pooled.extend(squared_mahalanobis(
                        &detect_markers(&view.image, &dict, &params).unwrap(),
                        &view.markers,
                    ));
                }
            }
            let (mean, n) = (
                pooled.iter().sum::<f64>() / pooled.len() as f64,
                pooled.len(),
            );
            // χ²(2) has variance 4; the four corners of a marker share its edges, so count
            // markers, not corners, for the standard error of the mean (conservative).
            let se = (pooled.iter().map(|m| (m - mean).powi(2)).sum::<f64>()
                / (n - 1) as f64
                / (n / 4) as f64)
                .sqrt();
            eprintln!(
                "{:>24}: mean e'C^-1e over {n} corners (8 noise seeds) {mean:.2} ± {se:.2}",
                cond.name
            );
            // Measured (debug build, these seeds): 2.04 ± 0.18 with blur 1.5 and noise 2 — the
            // covariance is right; 3.17 ± 0.48 under an illumination gradient, which the edge
            // model (constant dark and bright sides) does not have: there the reported σ is about
            // √(3.17/2) ≈ 1.26 times too small. Each bound is the measured mean ± 2.5–3 SE, so a
            // covariance off by 20 % in σ where the model holds (mean 2.9 or 1.4) fails. The old
            // bound, 0.5–8, accepted a σ off by a factor of 2 either way.
            let (low, high) = if cond.settings.gradient == [0.0, 0.0] {
                (1.6, 2.6)
            } else {
                (2.0, 4.5)
            };
            assert!(
                (low..=high).contains(&mean),
                "{}: reported corner covariance inconsistent: mean e'C^-1e = {mean:.2} ± {se:.2} over {n} corners, accepted {low}–{high}",
                cond.name
            );
        }
        assert!(
            r_ours <= r_cv,
            "{}: ours {r_ours:.4} px worse than OpenCV {r_cv:.4} px",
            cond.name
        );
        if cond.name == "clean" {
            assert!(r_ours < 0.05, "clean renders: {r_ours:.4} px");
        }
    }
}

/// Small markers (≈30 px, 5 px cells) far away and tilted, with blur and noise: all found by
/// both; ours no worse than OpenCV's CORNER_REFINE_SUBPIX.
#[test]
fn small_markers_far_away() {
    let dir = common::temp_dir("detect-small");
    let cam = common::test_camera();
    let target = common::four_marker_target();
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let poses = [
        common::look_at_target([0.05, 0.05], 1.2, [0.2, 0.1, 0.3], [0.1, 0.05]),
        common::look_at_target([0.05, 0.05], 1.1, [-0.4, 0.3, 1.9], [-0.15, -0.1]),
        common::look_at_target([0.05, 0.05], 1.3, [0.5, -0.2, -0.7], [0.2, -0.12]),
    ];
    let settings = RenderSettings {
        blur_sigma_px: 0.7,
        noise_sigma: 2.0,
        seed: 3,
        ..Default::default()
    };
    let (mut ours_sq, mut cv_sq, mut paths, mut truths) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, pose) in poses.iter().enumerate() {
        let view = render_view(&cam, pose, &target, &settings).unwrap();
        let p = dir.join(format!("small{k}.png"));
        common::save_png(&view.image, &p);
        let found = detect_markers(
            &image::open(&p).unwrap().to_luma8(),
            &dict,
            &DetectorParams::default(),
        )
        .unwrap();
        assert_eq!(
            found.len(),
            4,
            "{}: ids {:?}",
            p.display(),
            found.iter().map(|m| m.id).collect::<Vec<_>>()
        );
        ours_sq.extend(common::corner_sq_errors(
            &view.markers,
            &ours(&found),
            "small",
        ));
        paths.push(p.to_str().unwrap().to_string());
        truths.push(view.markers);
    }
    let mut args = vec!["detect", "DICT_4X4_50", "subpix"];
    args.extend(paths.iter().map(|s| s.as_str()));
    let cv = common::run_py("aruco_reference.py", &args);
    for (k, t) in truths.iter().enumerate() {
        cv_sq.extend(common::corner_sq_errors(
            t,
            &common::parse_detections(&cv[k]),
            &paths[k],
        ));
    }
    let (r_ours, r_cv) = (common::rms(&ours_sq), common::rms(&cv_sq));
    eprintln!(
        "small markers: corner RMS vs truth: ours {r_ours:.4} px, OpenCV subpix {r_cv:.4} px"
    );
    assert!(r_ours <= r_cv, "ours {r_ours:.4} vs OpenCV {r_cv:.4}");
}

/// Paste OpenCV-generated markers (every id) on a white canvas, each turned by id mod 4 quarter
/// turns; every marker must be found once, with the right id and corners within 0.1 px of the
/// marker's pixel edges.
#[test]
fn every_id_decodes_on_opencv_generated_markers() {
    let dir = common::temp_dir("all-ids");
    for (name, count) in [
        ("DICT_4X4_50", 50usize),
        ("DICT_5X5_100", 100),
        ("DICT_6X6_250", 250),
        ("DICT_7X7_50", 50),
        ("DICT_ARUCO_ORIGINAL", 1024),
    ] {
        let sub = dir.join(name);
        std::fs::create_dir_all(&sub).unwrap();
        let side = 48u32;
        let ids: Vec<String> = (0..count).map(|i| i.to_string()).collect();
        let mut args = vec!["markers", name, "48", "1", sub.to_str().unwrap()];
        args.extend(ids.iter().map(|s| s.as_str()));
        common::run_py("aruco_reference.py", &args);
        let dict = Dictionary::predefined(name).unwrap();
        let pitch = side + 24;
        let per_row = (count as f64).sqrt().ceil() as u32;
        let rows = (count as u32).div_ceil(per_row);
        let mut canvas =
            GrayImage::from_pixel(per_row * pitch + 24, rows * pitch + 24, image::Luma([255]));
        let mut expected = Vec::new();
        for id in 0..count {
            let tile = image::open(sub.join(format!("marker_{id}.png")))
                .unwrap()
                .to_luma8();
            // Cross-check our generator on the way (priority-1 property, every id).
            assert_eq!(
                tile,
                generate_marker_image(&dict, id, side, 1).unwrap(),
                "{name} id {id}"
            );
            let turns = id % 4;
            let mut t = tile;
            for _ in 0..turns {
                t = image::imageops::rotate90(&t);
            }
            let (ox, oy) = (
                24 + (id as u32 % per_row) * pitch,
                24 + (id as u32 / per_row) * pitch,
            );
            image::imageops::replace(&mut canvas, &t, ox as i64, oy as i64);
            // Marker corners in tile pixel coordinates, then turned clockwise like the tile.
            let s = side as f64;
            let mut c = [
                [-0.5, -0.5],
                [s - 0.5, -0.5],
                [s - 0.5, s - 0.5],
                [-0.5, s - 0.5],
            ];
            for _ in 0..turns {
                c = c.map(|[x, y]| [s - 1.0 - y, x]);
            }
            expected.push(c.map(|[x, y]| Point2::new(x + ox as f64, y + oy as f64)));
        }
        let found = detect_markers(&canvas, &dict, &DetectorParams::default()).unwrap();
        let mut seen = vec![0; count];
        for m in &found {
            seen[m.id] += 1;
            // A marker equal to its own rotation (ARUCO_ORIGINAL id 1023) has no defined first
            // corner: accept any cyclic order for it.
            let code = dict.code(m.id).unwrap();
            let symmetric = (1..4).any(|r| rotate_code(code, dict.marker_size, r) == code);
            let shifts: Vec<usize> = if symmetric { (0..4).collect() } else { vec![0] };
            let err = shifts
                .iter()
                .map(|&s| {
                    (0..4)
                        .map(|k| (m.corners[(k + s) % 4] - expected[m.id][k]).norm())
                        .fold(0.0, f64::max)
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                err < 0.1,
                "{name} id {}: a corner is off by {err:.3} px",
                m.id
            );
        }
        let missing: Vec<usize> = (0..count).filter(|&i| seen[i] != 1).collect();
        assert!(
            missing.is_empty(),
            "{name}: ids not found exactly once: {missing:?}"
        );
        eprintln!("{name}: all {count} ids decoded, corners within 0.1 px");
    }
}
