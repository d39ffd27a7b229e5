//! `metrocell detect` on real image files: an OpenCV-identical marker printed on a page is found
//! with its id and its corners where the page puts them; a page without markers gives none; a
//! truncated file is named in the error and the other files are still processed.

use std::time::Duration;

use image::{GrayImage, Luma};
use metrocell_vision::aruco::{generate_marker_image, Dictionary};
use system_tests::{bin, piped, run};

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-detect-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// A 400×400 white page with marker 7 of DICT_4X4_50 (240 px, 1-cell border) at (100, 100).
fn page_with_marker() -> GrayImage {
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let marker = generate_marker_image(&dict, 7, 240, 1).unwrap();
    let mut page = GrayImage::from_pixel(400, 400, Luma([255]));
    image::imageops::replace(&mut page, &marker, 100, 100);
    page
}

#[test]
fn detect_finds_the_printed_marker_where_it_is() {
    let marker_png = tmp("marker.png");
    page_with_marker().save(&marker_png).unwrap();
    let blank_png = tmp("blank.png");
    GrayImage::from_pixel(400, 400, Luma([200]))
        .save(&blank_png)
        .unwrap();
    let out = run(
        piped(bin("metrocell"))
            .arg("detect")
            .arg(&marker_png)
            .arg(&blank_png)
            .args(["--family", "DICT_4X4_50", "--json"]),
        Duration::from_secs(30),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<serde_json::Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2, "one JSON line per image");
    let det = lines[0]["detections"].as_array().unwrap();
    assert_eq!(det.len(), 1, "{:?}", lines[0]);
    assert_eq!(det[0]["id"], 7);
    // Pixel centres at integer coordinates: the marker's outer edge runs along x = 99.5 and 339.5.
    let expect = [[99.5, 99.5], [339.5, 99.5], [339.5, 339.5], [99.5, 339.5]];
    for (c, e) in det[0]["corners"].as_array().unwrap().iter().zip(expect) {
        let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
        assert!(
            (x - e[0]).abs() < 0.1 && (y - e[1]).abs() < 0.1,
            "corner ({x}, {y}) expected {e:?}"
        );
    }
    assert_eq!(
        lines[1]["detections"].as_array().unwrap().len(),
        0,
        "no false positive on a blank page"
    );
}

#[test]
fn truncated_image_is_named_and_the_rest_still_processed() {
    let good = tmp("good.png");
    page_with_marker().save(&good).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let bad = tmp("truncated.png");
    std::fs::write(&bad, &bytes[..bytes.len() / 3]).unwrap();
    let out = run(
        piped(bin("metrocell"))
            .arg("detect")
            .arg(&bad)
            .arg(&good)
            .args(["--family", "DICT_4X4_50", "--json"]),
        Duration::from_secs(30),
    );
    assert_eq!(
        out.status.code(),
        Some(1),
        "an unreadable image makes the exit code 1"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("truncated.png") && !err.contains("panicked"),
        "{err}"
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        stdout.contains("good.png") && stdout.contains("\"id\":7"),
        "the good image is still processed: {stdout}"
    );
}
