//! The `metrocell-camera` binary over DDS in a private network namespace: files (8-bit PNG,
//! 16-bit TIFF, a truncated PNG in between) are published as sensor_msgs/Image + CameraInfo with
//! the configured frame_id and increasing stamps (`stamp_source:=now`: looping replays the files); the truncated file is skipped and named in a
//! warning, and the node carries on. The fiducial node (the workspace's `metrocell-fiducial`
//! binary, built beside this test's by `cargo build --workspace --bins`, which `tests/run` does)
//! runs on the camera's frames: every frame it answers has the one marker, and the test prints
//! the frame-in → detection-out latency.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-camera-node --test camera_over_dds -- --nocapture`

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_node::{qos, MetrocellNode};
use metrocell_vision::aruco::{generate_marker_image, Dictionary};

fn stamp(h: &metrocell_msgs::std_msgs::msg::Header) -> i64 {
    h.stamp.nanos()
}

#[test]
fn publishes_files_with_camera_info_and_skips_bad_ones() {
    metrocell_node::testing::require_isolated_network();
    let dir = std::env::temp_dir().join(format!("camera_node_it_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 640×480 frames with one 4x4_50 marker (id 5), as 8-bit PNG and 16-bit TIFF.
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let marker = generate_marker_image(&dict, 5, 120, 1).unwrap();
    let mut frame = image::GrayImage::from_pixel(640, 480, image::Luma([230]));
    image::imageops::overlay(&mut frame, &marker, 260, 180);
    frame.save(dir.join("f0.png")).unwrap();
    let f16 = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(640, 480, |x, y| {
        image::Luma([frame.get_pixel(x, y)[0] as u16 * 16])
    });
    f16.save(dir.join("f2.tiff")).unwrap();
    let png = std::fs::read(dir.join("f0.png")).unwrap();
    std::fs::write(dir.join("f1_truncated.png"), &png[..png.len() / 3]).unwrap();
    let info = dir.join("camera_info.yaml");
    std::fs::write(&info, "image_width: 640\nimage_height: 480\ncamera_name: cam\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [600.0, 0.0, 319.5, 0.0, 600.0, 239.5, 0.0, 0.0, 1.0]\ndistortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0.0, 0.0, 0.0, 0.0, 0.0]\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]\nprojection_matrix:\n  rows: 3\n  cols: 4\n  data: [600.0, 0.0, 319.5, 0.0, 0.0, 600.0, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0]\n").unwrap();

    let mut node = MetrocellNode::builder("camera_test_sub")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let images = node
        .subscription::<Image>("image", qos::sensor_data())
        .unwrap();
    let infos = node
        .subscription::<CameraInfo>("camera_info", qos::sensor_data())
        .unwrap();
    let detections = node
        .subscription::<FiducialDetectionArray>("fiducials", qos::reliable())
        .unwrap();
    let mut fiducial = system_tests::ChildGuard::spawn(
        Command::new(system_tests::bin("metrocell-fiducial"))
            .args([
                "--ros-args",
                "-p",
                "family:=DICT_4X4_50",
                "-p",
                "marker_size:=0.02",
            ])
            .stderr(Stdio::null()),
    );
    // Let discovery settle, then run the camera through the files several times.
    std::thread::sleep(Duration::from_secs(2));
    let child = Command::new(env!("CARGO_BIN_EXE_metrocell-camera"))
        .args([
            "--ros-args",
            "-p",
            &format!("path:={}", dir.display()),
            "-p",
            "rate:=20.0",
            "-p",
            "loop:=true",
            "-p",
            "frame_id:=cam_optical",
            "-p",
            "stamp_source:=now",
            "-p",
            &format!("camera_info_url:=file://{}", info.display()),
        ])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(8);
    let (mut got, mut got_info, mut lat) = (Vec::new(), 0, Vec::new());
    let mut sent: std::collections::HashMap<i64, Instant> = Default::default();
    while Instant::now() < deadline {
        while let Ok(Some((m, _))) = images.take() {
            sent.insert(stamp(&m.header), Instant::now());
            got.push(m);
        }
        while let Ok(Some((c, _))) = infos.take() {
            assert_eq!(
                (c.header.frame_id.as_str(), c.width, c.k[0]),
                ("cam_optical", 640, 600.0)
            );
            got_info += 1;
        }
        while let Ok(Some((d, _))) = detections.take() {
            let now_ns = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos() as i64;
            assert_eq!(d.detections.len(), 1, "one marker per frame");
            assert_eq!(d.detections[0].id, 5);
            lat.push((now_ns - stamp(&d.header)) as f64 * 1e-6);
        }
        std::thread::sleep(Duration::from_micros(500));
    }
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let _ = fiducial.child().kill();
    assert!(
        got.len() >= 10,
        "only {} images in 8 s at 20 fps",
        got.len()
    );
    assert!(got_info >= 10, "only {got_info} camera_info");
    let encodings: std::collections::BTreeSet<&str> =
        got.iter().map(|m| m.encoding.as_str()).collect();
    assert_eq!(
        encodings.into_iter().collect::<Vec<_>>(),
        ["mono16", "mono8"]
    );
    for w in got.windows(2) {
        assert!(stamp(&w[1].header) > stamp(&w[0].header), "stamps increase");
        assert_eq!(w[1].header.frame_id, "cam_optical");
    }
    let m16 = got.iter().find(|m| m.encoding == "mono16").unwrap();
    assert_eq!((m16.step, m16.data.len()), (1280, 1280 * 480));
    assert!(
        stderr.contains("f1_truncated.png"),
        "warning names the bad file: {stderr}"
    );
    // The mono8 frames (every other good frame) carry the marker the fiducial node must find;
    // allow for frames published before the fiducial node matched.
    let mono8 = got.iter().filter(|m| m.encoding == "mono8").count();
    assert!(
        lat.len() * 2 >= mono8,
        "fiducial node answered {} of {mono8} mono8 frames",
        lat.len()
    );
    lat.sort_by(f64::total_cmp);
    println!(
        "camera → fiducial over DDS, 640x480, 1 marker: median {:.2} ms, max {:.2} ms ({} frames)",
        lat[lat.len() / 2],
        lat[lat.len() - 1],
        lat.len()
    );
    let _ = sent;
    std::fs::remove_dir_all(&dir).unwrap();
}
