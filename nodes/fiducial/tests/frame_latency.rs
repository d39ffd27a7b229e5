//! Benchmark (ignored by default): frame-in → detection-out latency
//! through the `metrocell-fiducial` node over DDS at 640×480, 1920×1080 and 3840×2160, one
//! DICT_4X4_50 marker per frame. Latency = this process publishing the Image → this process
//! taking the FiducialDetectionArray with the same stamp (DDS both ways, the node's conversion and
//! detection included). Peer measured in the same run: the library's `detect_targets` on the same
//! frame in this process (same thread count as the node), interleaved with the node frame by frame
//! (library, node, library, node, …) so both see the same machine load; the ratio node / library
//! is what DDS, message conversion and scheduling add.
//!
//! Run: `tests/isolated cargo test -p metrocell-fiducial-node --test frame_latency -- --ignored --nocapture`
//! (add `--release` for the release-build latencies BENCHMARKS.md gives).

use std::process::Command;
use std::time::{Duration, Instant};

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::Image;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Kill;
use metrocell_node::{qos, MetrocellNode};
use metrocell_vision::aruco::{generate_marker_image, DetectorParams, Dictionary};
use metrocell_vision::{detect_targets, TargetFamily};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A grey frame with one marker whose side is a quarter of the frame height.
fn frame(w: u32, h: u32) -> image::GrayImage {
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let side = h / 4;
    let marker = generate_marker_image(&dict, 7, side, 1).unwrap();
    let mut f = image::GrayImage::from_pixel(w, h, image::Luma([200]));
    image::imageops::overlay(&mut f, &marker, (w / 3) as i64, (h / 3) as i64);
    f
}

#[test]
#[ignore = "benchmark: run in release with --ignored --nocapture inside tests/isolated"]
fn frame_in_to_detection_out_latency() {
    metrocell_node::testing::require_isolated_network();
    let _child = Kill(
        Command::new(env!("CARGO_BIN_EXE_metrocell-fiducial"))
            .args(["--ros-args", "-p", "family:=DICT_4X4_50"])
            .spawn()
            .unwrap(),
    );
    let mut node = MetrocellNode::builder("latency_test_camera")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let images = node
        .publisher::<Image>("image", qos::sensor_data())
        .unwrap();
    let detections = node
        .subscription::<FiducialDetectionArray>("fiducials", qos::reliable())
        .unwrap();
    let family = TargetFamily::parse("DICT_4X4_50", None, None).unwrap();
    let frames_per_size = 15;
    let mut stamp = 1_000_000_000i64;
    println!("| frame | node latency median (ms) | max (ms) | library detect median (ms) | ratio node / library | frames |");
    println!("|---|---|---|---|---|---|");
    for (w, h) in [(640u32, 480u32), (1920, 1080), (3840, 2160)] {
        let img = frame(w, h);
        let msg = |stamp: i64| Image {
            header: Header {
                stamp: Time::from_nanos(stamp),
                frame_id: "cam".into(),
            },
            height: h,
            width: w,
            encoding: "mono8".into(),
            is_bigendian: 0,
            step: w,
            data: img.as_raw().clone(),
        };
        let mut lib = Vec::new();
        // Warm-up until the node answers (discovery, first large samples), then one frame at a
        // time, each node frame right after a library detection of the same frame.
        let (mut lat, mut lost) = (Vec::new(), 0);
        let mut warm = false;
        let deadline = Instant::now() + Duration::from_secs(120);
        while lat.len() < frames_per_size {
            assert!(
                Instant::now() < deadline,
                "{w}x{h}: only {} frames answered ({lost} lost)",
                lat.len()
            );
            let t = Instant::now();
            let found = detect_targets(&img, &family, &DetectorParams::default(), None).unwrap();
            let lib_ms = t.elapsed().as_secs_f64() * 1e3;
            assert_eq!(found.len(), 1, "{w}x{h}: the library finds the marker");
            if warm {
                lib.push(lib_ms);
            }
            stamp += 1;
            let m = msg(stamp);
            let t0 = Instant::now();
            let _ = images.publish(m);
            let mut answered = false;
            while t0.elapsed() < Duration::from_secs(5) && !answered {
                while let Ok(Some((d, _))) = detections.take() {
                    if d.header.stamp.nanosec as i64 == stamp % 1_000_000_000 {
                        assert_eq!(d.detections.len(), 1, "{w}x{h}: one marker");
                        answered = true;
                    }
                }
                if !answered {
                    std::thread::sleep(Duration::from_micros(200));
                }
            }
            let elapsed = t0.elapsed().as_secs_f64() * 1e3;
            match (answered, warm) {
                (true, true) => lat.push(elapsed),
                (true, false) => warm = true,
                (false, _) => lost += 1,
            }
        }
        let (mut l2, lm) = (lat.clone(), median(&mut lib));
        let med = median(&mut l2);
        println!("| {w}×{h} | {med:.1} | {:.1} | {lm:.1} | {:.2} | {} ({lost} lost; {} library runs interleaved) |", l2[l2.len() - 1], med / lm, lat.len(), lib.len());
    }
}
