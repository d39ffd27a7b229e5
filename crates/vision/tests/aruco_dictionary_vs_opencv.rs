//! Dictionaries and marker images against OpenCV (opencv-contrib-python-headless).
mod common;

use metrocell_vision::aruco::{generate_marker_image, Dictionary};

/// Every predefined dictionary: same marker count, maxCorrectionBits, and byte list for all four
/// rotations of every marker (OpenCV's `bytesList`).
#[test]
fn all_predefined_dictionaries_are_bit_exact() {
    let mut checked = 0;
    for name in Dictionary::predefined_names() {
        let d = Dictionary::predefined(name).unwrap();
        let cv = common::run_py("aruco_reference.py", &["dict", name]);
        assert_eq!(
            cv["marker_size"].as_u64().unwrap() as usize,
            d.marker_size,
            "{name}"
        );
        assert_eq!(
            cv["max_correction_bits"].as_u64().unwrap() as u32,
            d.max_correction_bits,
            "{name}"
        );
        let bytes = cv["bytes"].as_array().unwrap();
        assert_eq!(bytes.len(), d.len(), "{name} marker count");
        for (id, row) in bytes.iter().enumerate() {
            let ours = d.opencv_byte_list(id).unwrap();
            // numpy shows (nbytes, 4); flattened it is OpenCV's memory order.
            let theirs: Vec<u8> = row
                .as_array()
                .unwrap()
                .iter()
                .flat_map(|b| {
                    b.as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_u64().unwrap() as u8)
                })
                .collect();
            assert_eq!(ours, theirs, "{name} id {id}");
            checked += 1;
        }
    }
    assert!(checked > 8000, "checked {checked} markers");
}

/// Marker images pixel-equal to cv2.aruco.generateImageMarker, including sizes that are not a
/// multiple of the cell count (nearest-neighbour rounding) and wider borders.
#[test]
fn marker_images_are_pixel_equal_to_opencv() {
    let dir = common::temp_dir("marker-images");
    let cases: &[(&str, u32, u32, &[usize])] = &[
        ("DICT_4X4_50", 60, 1, &[0, 1, 17, 49]),
        ("DICT_4X4_1000", 97, 1, &[3, 999]),
        ("DICT_5X5_100", 200, 1, &[0, 42, 99]),
        ("DICT_6X6_250", 123, 2, &[7, 249]),
        ("DICT_7X7_50", 9, 1, &[5]),
        ("DICT_ARUCO_ORIGINAL", 71, 1, &[0, 1023]),
        ("DICT_APRILTAG_36H11", 333, 1, &[586]),
    ];
    let mut compared = 0;
    for &(name, side, border, ids) in cases {
        let sub = dir.join(format!("{name}_{side}_{border}"));
        std::fs::create_dir_all(&sub).unwrap();
        let id_strs: Vec<String> = ids.iter().map(|i| i.to_string()).collect();
        let side_s = side.to_string();
        let border_s = border.to_string();
        let mut args = vec![
            "markers",
            name,
            side_s.as_str(),
            border_s.as_str(),
            sub.to_str().unwrap(),
        ];
        args.extend(id_strs.iter().map(|s| s.as_str()));
        common::run_py("aruco_reference.py", &args);
        let d = Dictionary::predefined(name).unwrap();
        for &id in ids {
            let ours = generate_marker_image(&d, id, side, border).unwrap();
            let theirs = image::open(sub.join(format!("marker_{id}.png")))
                .unwrap()
                .to_luma8();
            assert_eq!(ours.dimensions(), theirs.dimensions());
            let diff = ours
                .pixels()
                .zip(theirs.pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(
                diff, 0,
                "{name} id {id} side {side} border {border}: {diff} pixels differ"
            );
            compared += 1;
        }
    }
    assert_eq!(compared, 15);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    assert!(Dictionary::predefined("DICT_3X3_1").is_err());
    let d = Dictionary::predefined("DICT_4X4_50").unwrap();
    assert!(d.code(50).is_err());
    assert!(generate_marker_image(&d, 0, 5, 1).is_err());
    assert!(generate_marker_image(&d, 0, 60, 0).is_err());
}
