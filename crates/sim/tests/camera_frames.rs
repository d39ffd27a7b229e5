//! Camera frames in a bag: every camera frame request of the quick demo cell becomes a mono8
//! `sensor_msgs/Image` on /camera/image_raw with its CameraInfo's stamp; the bytes read back
//! are the renderer's image, and ArUco detection on the decoded image finds the plate's four
//! markers with corners within 0.1 px RMS of the renderer's ground truth (noise-free render;
//! 0.8 px optical blur, as real optics band-limit the image).

use std::path::Path;

use metrocell_bag::{BagReader, MessageFilter};
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_simulation::sim_time::{parse_start_time, stamp_ns, DEFAULT_START_TIME};
use metrocell_simulation::{
    write_bag, BagOptions, CameraIntrinsics, FrameRendering, MessageConverter,
};
use metrocell_twin::{Cell, Sample, Simulation};
use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};
use metrocell_vision::RenderSettings;

const DURATION: f64 = 12.0;
const SEED: u64 = 11;

fn demo() -> Cell {
    Cell::from_path(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/quick_demo.yaml"),
    )
    .unwrap()
}

fn decode<T: serde::de::DeserializeOwned>(data: &[u8]) -> T {
    assert_eq!(&data[..4], &[0, 1, 0, 0], "encapsulation header");
    rustdds::serialization::from_bytes::<T, byteorder::LittleEndian>(&data[4..])
        .unwrap()
        .0
}

fn noise_free() -> FrameRendering {
    FrameRendering {
        settings: RenderSettings {
            supersampling: 8,
            blur_sigma_px: 0.8,
            noise_sigma: 0.0,
            ..RenderSettings::default()
        },
    }
}

/// Detects the plate's markers on `gray`: all four must be found; returns the sum of squared
/// corner errors against the render's ground truth (px²) and the number of corners.
fn plate_corner_errors(
    gray: &image::GrayImage,
    truth: &metrocell_vision::RenderedView,
) -> (f64, usize) {
    let found = detect_markers(
        gray,
        &Dictionary::predefined("DICT_4X4_50").unwrap(),
        &DetectorParams::default(),
    )
    .unwrap();
    let mut ids: Vec<usize> = found.iter().map(|d| d.id).collect();
    ids.sort();
    assert_eq!(ids, [0, 1, 2, 3], "all four plate markers");
    let mut sq = 0.0;
    for d in &found {
        let t = truth.markers.iter().find(|t| t.id == d.id).unwrap();
        sq += d
            .corners
            .iter()
            .zip(&t.corners)
            .map(|(a, b)| (a - b).norm_squared())
            .sum::<f64>();
    }
    (sq, 4 * found.len())
}

#[test]
fn rendered_frames_in_the_bag_decode_and_detect_at_the_ground_truth() {
    let dir = std::env::temp_dir().join(format!("metrocell-sim-frames-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let options = BagOptions {
        frames: Some(noise_free()),
        ..BagOptions::default()
    };
    let summary = write_bag(demo(), DURATION, SEED, &dir.join("bag"), &options, |_| {}).unwrap();
    let n_frames = summary.messages_per_topic["/camera/image_raw"];
    assert!(
        n_frames >= 1,
        "the demo's first dwell must give a frame within {DURATION} s"
    );
    assert_eq!(n_frames, summary.messages_per_topic["/camera/camera_info"]);

    // Ground truth: the same requests (same cell and seed), rendered by the same renderer.
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let converter = MessageConverter::new(&demo(), start, CameraIntrinsics::default())
        .unwrap()
        .with_frames(noise_free(), SEED)
        .unwrap();
    let renderer = converter.frames().unwrap();
    let sim = Simulation::new(demo(), DURATION, SEED).unwrap();
    let requests: Vec<_> = sim
        .samples()
        .filter_map(|s| {
            if let Sample::CameraFrameRequest(r) = s {
                Some(r)
            } else {
                None
            }
        })
        .collect();
    assert_eq!(requests.len() as u64, n_frames);

    let reader = BagReader::open(dir.join("bag")).unwrap();
    assert_eq!(
        reader.topic("/camera/image_raw").unwrap().type_name,
        "sensor_msgs/msg/Image"
    );
    let msgs = reader
        .read_all(&MessageFilter {
            topics: Some(vec![
                "/camera/image_raw".into(),
                "/camera/camera_info".into(),
            ]),
            ..MessageFilter::default()
        })
        .unwrap();
    let infos: Vec<u64> = msgs
        .iter()
        .filter(|m| m.topic == "/camera/camera_info")
        .map(|m| {
            let i: CameraInfo = decode(&m.data);
            i.header.stamp.nanos() as u64
        })
        .collect();
    let images: Vec<_> = msgs
        .iter()
        .filter(|m| m.topic == "/camera/image_raw")
        .collect();
    let (mut sq, mut n) = (0.0, 0usize);
    for (k, (m, req)) in images.iter().zip(&requests).enumerate() {
        let img: Image = decode(&m.data);
        let stamp = img.header.stamp.nanos() as u64;
        assert_eq!(stamp, infos[k], "image and its CameraInfo share the stamp");
        assert_eq!(stamp, stamp_ns(start, req.t));
        assert_eq!(
            (
                img.width,
                img.height,
                img.step,
                img.encoding.as_str(),
                img.is_bigendian
            ),
            (2448, 2048, 2448, "mono8", 0)
        );
        let truth = renderer.render(req, stamp).unwrap();
        assert!(
            img.data == *truth.image.as_raw(),
            "frame {k}: bag bytes are the rendered image"
        );
        let gray = image::GrayImage::from_raw(img.width, img.height, img.data).unwrap();
        let (frame_sq, frame_n) = plate_corner_errors(&gray, &truth);
        sq += frame_sq;
        n += frame_n;
    }
    let rms = (sq / n as f64).sqrt();
    println!("{n} corners, RMS vs ground truth {rms:.4} px");
    assert!(rms < 0.1, "corner RMS {rms} px");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A fisheye (`equidistant`) lens stated in the cell: the bag's CameraInfo carries that model and
/// its four coefficients, the calibration it states is the lens the frames were drawn with, and
/// the markers on the frames detect at the ground truth.
#[test]
fn a_fisheye_lens_in_the_cell_is_rendered_and_published() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/quick_demo.yaml");
    let text = std::fs::read_to_string(path).unwrap();
    assert_eq!(text.matches("    delay: 1 s\n").count(), 1);
    let lens = "    intrinsics: {width: 1600, height: 1200, fx: 700 px, fy: 702 px, cx: 801.5 px, cy: 598.5 px, model: equidistant, distortion: [0.05, -0.01, 0.002, -0.0004]}\n";
    let text = text.replace("    delay: 1 s\n", &format!("    delay: 1 s\n{lens}"));
    let cell = || Cell::from_yaml_str(&text, "fisheye_demo.yaml").unwrap();
    let dir = std::env::temp_dir().join(format!("metrocell-sim-fisheye-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let options = BagOptions {
        frames: Some(noise_free()),
        ..BagOptions::default()
    };
    write_bag(cell(), DURATION, SEED, &dir.join("bag"), &options, |_| {}).unwrap();

    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let converter = MessageConverter::new(&cell(), start, CameraIntrinsics::default())
        .unwrap()
        .with_frames(noise_free(), SEED)
        .unwrap();
    let renderer = converter.frames().unwrap();
    let reader = BagReader::open(dir.join("bag")).unwrap();
    let msgs = reader
        .read_all(&MessageFilter {
            topics: Some(vec![
                "/camera/image_raw".into(),
                "/camera/camera_info".into(),
            ]),
            ..MessageFilter::default()
        })
        .unwrap();
    let info: CameraInfo = decode(
        &msgs
            .iter()
            .find(|m| m.topic == "/camera/camera_info")
            .unwrap()
            .data,
    );
    assert_eq!(
        (info.distortion_model.as_str(), info.d.as_slice()),
        ("equidistant", &[0.05, -0.01, 0.002, -0.0004][..])
    );
    assert_eq!(
        metrocell_camera_model::camera_model_from_msg(&info).unwrap(),
        renderer.camera,
        "the published calibration is the rendering lens"
    );

    let sim = Simulation::new(cell(), DURATION, SEED).unwrap();
    let request = sim
        .samples()
        .find_map(|s| {
            if let Sample::CameraFrameRequest(r) = s {
                Some(r)
            } else {
                None
            }
        })
        .unwrap();
    let img: Image = decode(
        &msgs
            .iter()
            .find(|m| m.topic == "/camera/image_raw")
            .unwrap()
            .data,
    );
    assert_eq!((img.width, img.height), (1600, 1200));
    let truth = renderer
        .render(&request, img.header.stamp.nanos() as u64)
        .unwrap();
    assert!(img.data == *truth.image.as_raw());
    let gray = image::GrayImage::from_raw(img.width, img.height, img.data).unwrap();
    let (sq, n) = plate_corner_errors(&gray, &truth);
    let rms = (sq / n as f64).sqrt();
    println!("fisheye lens: {n} corners, RMS vs ground truth {rms:.4} px");
    assert!(rms < 0.1, "corner RMS {rms} px");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The twin's camera reading is the shared model's (crates/model `camera`): the pixels of the
/// plate's marker corners it predicts for every frame request are the renderer's ground-truth
/// corners (crates/vision's projection of the request's poses, an independent implementation
/// of the pinhole + Brown–Conrady lens) to 1e-9 px — for the default lens, a Brown–Conrady lens
/// with distortion, a turned five-axis table, a delta and an arm.
#[test]
fn the_models_predicted_corners_are_the_rendered_ground_truth() {
    let lens = "    intrinsics: {width: 2048, height: 1536, fx: 2600 px, fy: 2605 px, cx: 1023.5 px, cy: 767.5 px, model: plumb_bob, distortion: [-0.12, 0.05, 0.0007, -0.0004, -0.01]}\n";
    let demo_text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/quick_demo.yaml"),
    )
    .unwrap();
    let arm = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/serial_arm_ur5.yaml"),
    )
    .unwrap();
    let arm = arm.replace("  machine_state: {rate: 20 Hz}", "  camera: {mount: {translation: [30 mm, 0 mm, 20 mm], euler_xyz: [0 deg, 0 deg, 90 deg]}, delay: 1 s}\n  machine_state: {rate: 20 Hz}");
    let example = |n: &str| {
        Cell::from_path(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../twin/examples/cells")
                .join(n),
        )
        .unwrap()
    };
    let cells = [
        ("quick_demo", demo()),
        (
            "quick_demo + lens",
            Cell::from_yaml_str(
                &demo_text.replace("    delay: 1 s\n", &format!("    delay: 1 s\n{lens}")),
                "lens.yaml",
            )
            .unwrap(),
        ),
        ("five_axis_table", example("five_axis_table.yaml")),
        ("delta_printer", example("delta_printer.yaml")),
        (
            "ur5 + camera",
            Cell::from_yaml_str(&arm, "arm_camera.yaml").unwrap(),
        ),
    ];
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let mut frames = 0;
    for (name, cell) in cells {
        let converter = MessageConverter::new(&cell, start, CameraIntrinsics::default())
            .unwrap()
            .with_frames(noise_free(), SEED)
            .unwrap();
        let renderer = converter.frames().unwrap();
        let sim = Simulation::new(cell, 60.0, SEED).unwrap();
        for r in sim
            .samples()
            .filter_map(|s| {
                if let Sample::CameraFrameRequest(r) = s {
                    Some(r)
                } else {
                    None
                }
            })
            .take(4)
        {
            let truth = renderer.render(&r, stamp_ns(start, r.t)).unwrap();
            let corners = r
                .corners
                .as_ref()
                .expect("pinhole + Brown–Conrady lenses have predicted corners");
            let mut worst = 0.0f64;
            for m in &truth.markers {
                for (k, c) in m.corners.iter().enumerate() {
                    worst = worst.max((corners[4 * m.id + k] - c.coords).norm());
                }
            }
            assert_eq!(truth.markers.len(), 4);
            assert!(
                worst < 1e-9,
                "{name} t = {}: predicted corners {worst:e} px from the rendered ones",
                r.t
            );
            frames += 1;
        }
    }
    assert!(frames >= 15, "{frames} frames compared");
}
