//! The `metrocell-camera` binary stamps file frames with their capture time: the file's
//! modification time by default, or the time in the file name with `stamp_source:=filename`.
//! Over DDS in a private network namespace; each case in its own ROS namespace.
//!
//! Run: `tests/isolated cargo test -p metrocell-camera-node --test capture_stamps_over_dds`

use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, UNIX_EPOCH};

use metrocell_msgs::sensor_msgs::msg::Image;
use metrocell_node::{qos, MetrocellNode};

fn stamp(h: &metrocell_msgs::std_msgs::msg::Header) -> i64 {
    h.stamp.nanos()
}

fn write_frame(path: &Path, mtime_ns: u64) {
    image::GrayImage::from_fn(32, 24, |x, y| image::Luma([(x * 7 + y) as u8]))
        .save(path)
        .unwrap();
    let t = UNIX_EPOCH + Duration::from_nanos(mtime_ns);
    std::fs::File::options()
        .write(true)
        .open(path)
        .unwrap()
        .set_modified(t)
        .unwrap();
}

/// Run the camera on `dir` (looping) in namespace `ns` with `extra` parameters and collect the
/// stamps and frame_ids of the frames it publishes for a few seconds.
fn stamps_published(ns: &str, dir: &Path, extra: &[&str]) -> (BTreeSet<i64>, BTreeSet<String>) {
    let mut node = MetrocellNode::builder("stamp_test_sub")
        .namespace(ns)
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let images = node
        .subscription::<Image>("image", qos::sensor_data())
        .unwrap();
    let mut args = vec![
        "--ros-args".to_string(),
        "-r".into(),
        format!("__ns:={ns}"),
        "-p".into(),
        format!("path:={}", dir.display()),
    ];
    args.extend(
        [
            "-p",
            "rate:=20.0",
            "-p",
            "loop:=true",
            "-p",
            "frame_id:=cam_optical",
        ]
        .map(String::from),
    );
    for e in extra {
        args.extend(["-p".to_string(), e.to_string()]);
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_metrocell-camera"))
        .args(&args)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let (mut stamps, mut frames) = (BTreeSet::new(), BTreeSet::new());
    let deadline = Instant::now() + Duration::from_secs(6);
    while Instant::now() < deadline {
        while let Ok(Some((m, _))) = images.take() {
            stamps.insert(stamp(&m.header));
            frames.insert(m.header.frame_id.clone());
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill();
    let _ = child.wait();
    (stamps, frames)
}

#[test]
fn file_frames_carry_their_modification_time_or_the_time_in_their_name() {
    metrocell_node::testing::require_isolated_network();
    let dir = std::env::temp_dir().join(format!("camera_stamps_it_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (by_mtime, by_name) = (dir.join("mtime"), dir.join("name"));
    std::fs::create_dir_all(&by_mtime).unwrap();
    std::fs::create_dir_all(&by_name).unwrap();
    // Capture times far from "now", with nanoseconds a float would lose.
    let (t1, t2) = (1_600_000_000_123_456_789u64, 1_600_000_001_987_654_321u64);
    write_frame(&by_mtime.join("a.png"), t1);
    write_frame(&by_mtime.join("b.png"), t2);
    // Names carry the stamp; the files' mtimes are deliberately different.
    write_frame(&by_name.join("cam0_1700000000.000000001.png"), t1);
    write_frame(&by_name.join("cam0_1700000002.5.png"), t2);

    let (stamps, frames) = stamps_published("/by_mtime", &by_mtime, &[]);
    assert_eq!(
        stamps,
        BTreeSet::from([t1 as i64, t2 as i64]),
        "default stamp_source mtime"
    );
    assert_eq!(frames, BTreeSet::from(["cam_optical".to_string()]));

    let (stamps, _) = stamps_published(
        "/by_name",
        &by_name,
        &["stamp_source:=filename", "stamp_pattern:=cam0_{s}.png"],
    );
    assert_eq!(
        stamps,
        BTreeSet::from([1_700_000_000_000_000_001, 1_700_000_002_500_000_000]),
        "stamp_source filename"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
