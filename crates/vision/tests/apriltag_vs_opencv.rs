//! AprilTag 36h11 (and 25h9, 16h5) markers printed by OpenCV's generator (cv2.aruco with
//! DICT_APRILTAG_*, the AprilTag bit layout OpenCV uses): every id decodes with its exact id, and
//! nothing is reported on images without tags or with tags of another family.
mod common;

use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};

fn check_family(name: &str, side_px: &str) {
    let dir = common::temp_dir(&format!("apriltag-{name}"));
    let sheets = common::run_py(
        "apriltag_images.py",
        &[dir.to_str().unwrap(), name, side_px],
    );
    let dict = Dictionary::predefined(name).unwrap();
    let mut total = 0;
    for sheet in sheets.as_array().unwrap() {
        let path = sheet["path"].as_str().unwrap();
        let want: Vec<usize> = sheet["ids"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        let img = image::open(path).unwrap().to_luma8();
        let mut got: Vec<usize> = detect_markers(&img, &dict, &DetectorParams::default())
            .unwrap()
            .iter()
            .map(|m| m.id)
            .collect();
        got.sort();
        assert_eq!(
            got, want,
            "{path}: ids decoded (OpenCV found {})",
            sheet["opencv_ids"]
        );
        total += want.len();
    }
    assert_eq!(total, dict.len(), "{name}: every id generated");
}

#[test]
fn every_opencv_apriltag_36h11_decodes() {
    check_family("DICT_APRILTAG_36h11", "64");
}

#[test]
fn every_opencv_apriltag_25h9_and_16h5_decodes() {
    check_family("DICT_APRILTAG_25h9", "56");
    check_family("DICT_APRILTAG_16h5", "48");
}

#[test]
fn no_apriltag_on_other_families_or_plain_images() {
    let dir = common::temp_dir("apriltag-negatives");
    let sheets = common::run_py(
        "apriltag_images.py",
        &[dir.to_str().unwrap(), "DICT_4X4_250", "64"],
    );
    let tag = Dictionary::predefined("DICT_APRILTAG_36h11").unwrap();
    for sheet in sheets.as_array().unwrap() {
        let img = image::open(sheet["path"].as_str().unwrap())
            .unwrap()
            .to_luma8();
        let found = detect_markers(&img, &tag, &DetectorParams::default()).unwrap();
        assert!(
            found.is_empty(),
            "{}: 36h11 false positives {:?}",
            sheet["path"],
            found.iter().map(|m| m.id).collect::<Vec<_>>()
        );
    }
    let blank = image::GrayImage::from_fn(640, 480, |x, y| {
        image::Luma([if (x / 40 + y / 40) % 2 == 0 { 30 } else { 225 }])
    });
    assert!(detect_markers(&blank, &tag, &DetectorParams::default())
        .unwrap()
        .is_empty());
}
