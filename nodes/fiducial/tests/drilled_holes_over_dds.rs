//! The `metrocell-fiducial` binary with `family:=drilled_holes` over DDS in a private network
//! namespace: a rendered seed-000 hole plate (6×6 squares of 10 mm, a 2 mm hole in each, holes
//! displaced from the square centres by a known error pattern) is published on
//! /camera/image_raw, where the simulator publishes its frames; the node (remapped onto it)
//! answers with one FiducialDetection per hole whose centre and covariance equal the library's
//! `detect_targets` on the same frame, whose centres lie on the projected true hole centres, and
//! whose header is the frame's (capture stamp and frame_id pass through).
//!
//! Run: `tests/isolated cargo test -p metrocell-fiducial-node --test drilled_holes_over_dds -- --nocapture`

use std::process::Command;
use std::time::{Duration, Instant};

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::Image;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Kill;
use metrocell_node::{qos, MetrocellNode};
use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{
    detect_targets, render_view, CameraModel, Distortion, PlanarTarget, RenderSettings,
    TargetFamily, TargetItem,
};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

const N: usize = 6;
const SQUARE: f64 = 0.010;

#[test]
fn hole_centres_over_dds_equal_the_library_and_the_truth() {
    metrocell_node::testing::require_isolated_network();
    // 0.1 mm/px on the plate: 100 px squares, 20 px holes.
    let cam = CameraModel::new(
        800,
        800,
        1000.0,
        1000.0,
        399.5,
        399.5,
        Distortion::BrownConrady([-0.05, 0.0, 0.0, 0.0, 0.0]),
    )
    .unwrap();
    let truth: Vec<[f64; 2]> = (0..N * N)
        .map(|k| {
            let (i, j) = ((k % N) as f64, (k / N) as f64);
            // up to ±0.25 mm off the nominal square centre
            [
                (i + 0.5) * SQUARE + 0.05e-3 * (i - 2.5),
                (j + 0.5) * SQUARE - 0.04e-3 * (i - 2.5) + 0.03e-3 * (j - 2.5),
            ]
        })
        .collect();
    let mut items = vec![TargetItem::Checkerboard {
        top_left: [0.0, 0.0],
        square: SQUARE,
        squares_x: N as u32,
        squares_y: N as u32,
        top_left_black: true,
    }];
    items.extend(truth.iter().map(|c| TargetItem::Hole {
        centre: *c,
        diameter: 0.002,
    }));
    let rot = UnitQuaternion::from_euler_angles(0.08, -0.06, 0.05);
    let pose = Isometry3::from_parts(
        Translation3::from(Vector3::new(0.0, 0.0, 0.1) - rot * Vector3::new(0.03, 0.03, 0.0)),
        rot,
    );
    let settings = RenderSettings {
        blur_sigma_px: 0.7,
        noise_sigma: 1.0,
        supersampling: 8,
        ..Default::default()
    };
    let view = render_view(&cam, &pose, &PlanarTarget { items }, &settings).unwrap();
    let truth_px: Vec<[f64; 2]> = truth
        .iter()
        .map(|c| {
            cam.project_camera_point(&(pose * Point3::new(c[0], c[1], 0.0)).coords)
                .unwrap()
        })
        .collect();

    // The library on the same frame: what the node must publish.
    let family = TargetFamily::parse("drilled_holes", Some((N - 1, N - 1)), None).unwrap();
    let expected = detect_targets(&view.image, &family, &DetectorParams::default(), None).unwrap();
    assert_eq!(
        expected.len(),
        N * N,
        "library found {} of {} holes",
        expected.len(),
        N * N
    );

    let _child = Kill(
        Command::new(env!("CARGO_BIN_EXE_metrocell-fiducial"))
            .args([
                "--ros-args",
                "-r",
                "image:=/camera/image_raw",
                "-p",
                "family:=drilled_holes",
                "-p",
                "board_cols:=5",
                "-p",
                "board_rows:=5",
            ])
            .spawn()
            .unwrap(),
    );
    let mut node = MetrocellNode::builder("holes_test_camera")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let images = node
        .publisher::<Image>("/camera/image_raw", qos::sensor_data())
        .unwrap();
    let detections = node
        .subscription::<FiducialDetectionArray>("fiducials", qos::reliable())
        .unwrap();
    let frame = |k: i64| Image {
        // A capture stamp far from now, with nanoseconds: it must come back unchanged.
        header: Header {
            stamp: Time {
                sec: 1_600_000_000 + k as i32,
                nanosec: 123_456_789,
            },
            frame_id: "plate_cam_optical".into(),
        },
        height: 800,
        width: 800,
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: 800,
        data: view.image.as_raw().clone(),
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut k = 0;
    let (sent_header, d) = 'outer: loop {
        assert!(
            Instant::now() < deadline,
            "no FiducialDetectionArray within 60 s"
        );
        let f = frame(k);
        let header = f.header.clone();
        let _ = images.publish(f);
        let wait = Instant::now() + Duration::from_secs(2);
        while Instant::now() < wait {
            if let Ok(Some((d, _))) = detections.take() {
                break 'outer (header, d);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        k += 1;
    };
    assert_eq!(
        d.header.frame_id, sent_header.frame_id,
        "frame_id passes through"
    );
    assert!(
        d.header.stamp.sec >= 1_600_000_000 && d.header.stamp.nanosec == 123_456_789,
        "capture stamp passes through: {:?}",
        d.header.stamp
    );
    assert_eq!((d.image_width, d.image_height), (800, 800));
    assert_eq!(d.detections.len(), N * N);
    let mut sq = 0.0;
    for (m, e) in d.detections.iter().zip(&expected) {
        assert_eq!(
            (m.family.as_str(), m.id as i64, m.has_pose),
            ("drilled_holes", e.id, false)
        );
        let c = e.corner_covariance[0];
        assert_eq!(
            m.corners,
            vec![e.corners[0].x, e.corners[0].y],
            "hole {}: node and library differ",
            e.id
        );
        assert_eq!(
            m.corner_covariance,
            vec![c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)]]
        );
        assert!(
            m.decision_margin > 0.5 && m.decision_margin <= 1.0,
            "contrast {}",
            m.decision_margin
        );
        let t = truth_px[e.id as usize];
        let err = ((m.corners[0] - t[0]).powi(2) + (m.corners[1] - t[1]).powi(2)).sqrt();
        let sigma = (c[(0, 0)] + c[(1, 1)]).sqrt();
        assert!(sigma > 0.0 && sigma < 0.05, "hole {}: σ {sigma} px", e.id);
        assert!(err < 0.1, "hole {}: {err:.3} px from the true centre", e.id);
        sq += err * err;
    }
    let rms = (sq / (N * N) as f64).sqrt();
    println!("drilled holes over DDS: {} holes, centre RMS {rms:.4} px ({:.2} µm on the plate) against the truth", N * N, rms * 100.0);
}
