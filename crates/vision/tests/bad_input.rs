//! Bad input returns errors naming what is wrong, never a panic.
use image::GrayImage;
use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};
use metrocell_vision::checkerboard::detect_checkerboard;
use metrocell_vision::edge_profile::{find_profile_edges, sample_line_profile};
use metrocell_vision::{
    render_view, CameraModel, Distortion, PlanarTarget, RenderSettings, TargetItem, VisionError,
};
use nalgebra::{Isometry3, Point2};

#[test]
fn errors_name_the_problem() {
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let tiny = GrayImage::new(8, 8);
    assert!(matches!(
        detect_markers(&tiny, &dict, &DetectorParams::default()),
        Err(VisionError::ImageTooSmall { .. })
    ));
    let img = GrayImage::from_pixel(64, 64, image::Luma([200]));
    let bad = DetectorParams {
        threshold_windows: vec![4],
        ..Default::default()
    };
    let e = detect_markers(&img, &dict, &bad).unwrap_err();
    assert!(e.to_string().contains("threshold_windows"), "{e}");
    assert!(detect_checkerboard(&img, 1, 5)
        .unwrap_err()
        .to_string()
        .contains("cols/rows"));
    assert!(matches!(
        detect_checkerboard(&img, 5, 4),
        Err(VisionError::NoSolution { .. })
    ));
    let e = sample_line_profile(&img, Point2::new(-3.0, 5.0), Point2::new(30.0, 5.0)).unwrap_err();
    assert!(e.to_string().contains("outside"), "{e}");
    assert!(find_profile_edges(&[1.0; 5], 1.5, 1.0).is_err());

    let cam = CameraModel::new(64, 64, 500.0, 500.0, 31.5, 31.5, Distortion::none()).unwrap();
    let pose = Isometry3::translation(0.0, 0.0, 1.0);
    let bad_marker = PlanarTarget {
        items: vec![TargetItem::Marker {
            dictionary: dict,
            id: 50,
            top_left: [0.0, 0.0],
            side: 0.05,
            border_bits: 1,
        }],
    };
    let e = render_view(&cam, &pose, &bad_marker, &RenderSettings::default()).unwrap_err();
    assert!(
        matches!(e, VisionError::MarkerIdOutOfRange { id: 50, .. }),
        "{e}"
    );
    let e = render_view(
        &cam,
        &pose,
        &PlanarTarget::default(),
        &RenderSettings {
            supersampling: 0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("supersampling"));
}
