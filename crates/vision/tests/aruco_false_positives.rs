//! No markers reported where there are none; error correction within the dictionary's capacity.
mod common;

use image::GrayImage;
use metrocell_vision::aruco::{detect_markers, generate_marker_image, DetectorParams, Dictionary};
use metrocell_vision::{render_view, RenderSettings};
use rand::{Rng, SeedableRng};

fn marker_free_images() -> Vec<(String, GrayImage)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
    let mut out = Vec::new();
    let (w, h) = (640u32, 480u32);
    for k in 0..3 {
        let sigma = [10.0, 30.0, 60.0][k];
        let img = GrayImage::from_fn(w, h, |_, _| {
            let g: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
            image::Luma([(128.0 + sigma * g).round().clamp(0.0, 255.0) as u8])
        });
        out.push((format!("noise{sigma}"), img));
    }
    out.push((
        "salt-and-pepper".into(),
        GrayImage::from_fn(w, h, |_, _| {
            image::Luma([if rng.random::<bool>() { 0 } else { 255 }])
        }),
    ));
    out.push((
        "gradient".into(),
        GrayImage::from_fn(w, h, |x, y| image::Luma([((x + y) * 255 / (w + h)) as u8])),
    ));
    out.push((
        "vignette".into(),
        GrayImage::from_fn(w, h, |x, y| {
            let r = ((x as f64 - 320.0).powi(2) + (y as f64 - 240.0).powi(2)).sqrt();
            image::Luma([(230.0 - r * 0.4) as u8])
        }),
    ));
    // Black squares and rectangles of random sizes on white (quads with all-black payloads).
    let mut rects = GrayImage::from_pixel(w, h, image::Luma([235]));
    for _ in 0..40 {
        let (s, t) = (rng.random_range(8..60u32), rng.random_range(8..60u32));
        let (x0, y0) = (rng.random_range(5..w - 70), rng.random_range(5..h - 70));
        for y in y0..y0 + t {
            for x in x0..x0 + s {
                rects.put_pixel(x, y, image::Luma([20]));
            }
        }
    }
    out.push(("black-rectangles".into(), rects));
    // Fine checkerboard directly in pixels and rendered checkerboards in perspective.
    out.push((
        "checker10px".into(),
        GrayImage::from_fn(w, h, |x, y| {
            image::Luma([if (x / 10 + y / 10) % 2 == 0 { 20 } else { 235 }])
        }),
    ));
    let cam = common::test_camera();
    let target = common::checkerboard_target();
    for (k, rpy) in [[0.0, 0.0, 0.1], [0.4, -0.3, 0.8], [-0.5, 0.2, 2.0]]
        .iter()
        .enumerate()
    {
        let pose = common::look_at_target([0.054, 0.042], 0.3, *rpy, [0.0, 0.0]);
        let v = render_view(
            &cam,
            &pose,
            &target,
            &RenderSettings {
                blur_sigma_px: 0.7,
                noise_sigma: 2.0,
                ..Default::default()
            },
        )
        .unwrap();
        out.push((format!("checkerboard-pose{k}"), v.image));
    }
    out
}

/// Zero detections on noise, gradients, random black rectangles and checkerboards, for small
/// (4X4_50), large (6X6_250) and ARUCO_ORIGINAL dictionaries. OpenCV's count is printed alongside.
#[test]
fn zero_false_positives_on_marker_free_images() {
    let dir = common::temp_dir("false-positives");
    let images = marker_free_images();
    let mut paths = Vec::new();
    for (name, img) in &images {
        let p = dir.join(format!("{name}.png"));
        common::save_png(img, &p);
        paths.push(p.to_str().unwrap().to_string());
    }
    for dname in ["DICT_4X4_50", "DICT_6X6_250", "DICT_ARUCO_ORIGINAL"] {
        let dict = Dictionary::predefined(dname).unwrap();
        let mut args = vec!["detect", dname, "none"];
        args.extend(paths.iter().map(|s| s.as_str()));
        let cv = common::run_py("aruco_reference.py", &args);
        let cv_total: usize = (0..images.len())
            .map(|k| cv[k].as_array().unwrap().len())
            .sum();
        let mut total = 0;
        for (name, img) in &images {
            let found = detect_markers(img, &dict, &DetectorParams::default()).unwrap();
            assert!(
                found.is_empty(),
                "{dname} on {name}: false detections {:?}",
                found.iter().map(|m| m.id).collect::<Vec<_>>()
            );
            total += found.len();
        }
        eprintln!(
            "{dname}: false positives over {} images: ours {total}, OpenCV {cv_total}",
            images.len()
        );
    }
}

/// Flipping payload cells: up to ⌊0.6·maxCorrectionBits⌋ flips are corrected and counted, one more
/// is rejected (DICT_6X6_50: maxCorrectionBits 6 → 3 correctable).
#[test]
fn bit_errors_are_corrected_up_to_capacity() {
    let dict = Dictionary::predefined("DICT_6X6_50").unwrap();
    assert_eq!(dict.max_correction_bits, 6);
    let side = 80u32; // 8 cells of 10 px
    let base = generate_marker_image(&dict, 17, side, 1).unwrap();
    let cells_to_flip = [(1u32, 1u32), (3, 4), (6, 2), (5, 5)];
    for flips in 0..=4usize {
        let mut m = base.clone();
        for &(r, c) in &cells_to_flip[..flips] {
            for y in r * 10..r * 10 + 10 {
                for x in c * 10..c * 10 + 10 {
                    let v = m.get_pixel(x, y)[0];
                    m.put_pixel(x, y, image::Luma([255 - v]));
                }
            }
        }
        let mut canvas = GrayImage::from_pixel(160, 160, image::Luma([255]));
        image::imageops::replace(&mut canvas, &m, 40, 40);
        let found = detect_markers(&canvas, &dict, &DetectorParams::default()).unwrap();
        if flips <= 3 {
            assert_eq!(found.len(), 1, "{flips} flips");
            assert_eq!((found[0].id, found[0].bit_errors), (17, flips as u32));
        } else {
            assert!(
                found.iter().all(|f| f.id != 17),
                "{flips} flips must not decode as 17"
            );
        }
    }
}
