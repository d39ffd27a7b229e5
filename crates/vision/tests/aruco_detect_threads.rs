//! The detector's output does not depend on the number of worker threads.
mod common;

use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};
use metrocell_vision::{render_view, RenderSettings};

#[test]
fn same_result_with_one_or_many_threads() {
    let cam = common::test_camera();
    let pose = &common::test_poses()[1];
    let settings = RenderSettings {
        blur_sigma_px: 1.0,
        noise_sigma: 3.0,
        ..Default::default()
    };
    let view = render_view(&cam, pose, &common::four_marker_target(), &settings).unwrap();
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let one = detect_markers(
        &view.image,
        &dict,
        &DetectorParams {
            threads: 1,
            ..Default::default()
        },
    )
    .unwrap();
    let many = detect_markers(
        &view.image,
        &dict,
        &DetectorParams {
            threads: 4,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(one.len(), 4);
    assert_eq!(one, many);
}
