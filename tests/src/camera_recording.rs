//! Photos taken "in the cell": image files published by the camera node over DDS and recorded
//! by `metrocell bag record`, as a user ingests a folder of photos into a recording. The
//! workflow commands' `--bag` must then give what their `--images` give.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use crate::{bin, interrupt, piped, require_isolated_network, run_ok, ChildGuard};

/// Publishes the files of `glob` once on `/camera/image_raw` (with `camera_info`) at 1 Hz, the
/// camera node holding the first frame until the recorder is matched, and records both topics
/// into `bag` on ROS domain `domain` (tests of one binary run in parallel: each its own domain).
/// Asserts that every file was recorded; returns `bag info`'s output.
pub fn record_photos(
    glob: &Path,
    camera_info: &Path,
    bag: &Path,
    domain: u32,
    files: usize,
) -> String {
    require_isolated_network();
    let _ = std::fs::remove_dir_all(bag);
    let domain = domain.to_string();
    let recorder = ChildGuard::spawn(
        piped(bin("metrocell"))
            .args([
                "bag",
                "record",
                "/camera/image_raw",
                "/camera/camera_info",
                "-o",
            ])
            .arg(bag)
            .env("ROS_DOMAIN_ID", &domain),
    );
    let mut camera = Command::new(bin("metrocell-camera"));
    camera
        .args([
            "--ros-args",
            "-r",
            "__ns:=/camera",
            "-r",
            "image:=image_raw",
            "-p",
        ])
        .arg(format!("path:={}", glob.display()))
        .arg("-p")
        .arg(format!("camera_info_url:={}", camera_info.display()))
        .args(["-p", "rate:=1.0", "-p", "wait_for_subscribers:=1"])
        .env("ROS_DOMAIN_ID", &domain);
    run_ok(&mut camera, Duration::from_secs(120));
    // the last frame's fragments are still being reassembled when the camera exits
    std::thread::sleep(Duration::from_secs(1));
    interrupt(recorder.pid());
    let out = recorder.wait_output(Duration::from_secs(30));
    assert!(
        out.status.success(),
        "bag record: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let info = run_ok(
        piped(bin("metrocell")).args(["bag", "info"]).arg(bag),
        Duration::from_secs(30),
    );
    let count = info
        .lines()
        .find(|l| l.contains("/camera/image_raw"))
        .and_then(|l| l.split("Count:").nth(1))
        .and_then(|r| r.split('|').next())
        .and_then(|c| c.trim().parse::<usize>().ok());
    assert_eq!(count, Some(files), "every photo recorded once:\n{info}");
    info
}

/// The photos of `glob` taken "in the cell" ([`record_photos`]) and measured from the recording by
/// `metrocell WORKFLOW measure --bag` with the recorded camera_info: asserts the table equals
/// `from_files` (what `--images` wrote) byte for byte.
pub fn recorded_photos_measure_the_same(
    workflow: &str,
    glob: &Path,
    camera_info: &Path,
    domain: u32,
    files: usize,
    from_files: &Path,
) {
    let dir = from_files.parent().expect("a table in a directory");
    let bag = dir.join(format!("{workflow}_bag"));
    record_photos(glob, camera_info, &bag, domain, files);
    let from_bag = dir.join(format!("{workflow}_from_bag.csv"));
    run_ok(
        piped(bin("metrocell"))
            .args([workflow, "measure", "--bag"])
            .arg(&bag)
            .arg("-o")
            .arg(&from_bag),
        Duration::from_secs(120),
    );
    assert_eq!(
        std::fs::read_to_string(&from_bag).unwrap(),
        std::fs::read_to_string(from_files).unwrap(),
        "{workflow} measure: the recording's table and the files' differ"
    );
}
