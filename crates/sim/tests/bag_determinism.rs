//! write_bag on the quick demo cell: counts per topic follow the cell's rates, every stamp is
//! start + t, the bytes read back decode to the same typed values, and two runs with the same
//! seed give byte-identical bags (a different seed does not).

use std::path::{Path, PathBuf};

use metrocell_bag::{BagReader, MessageFilter};
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::{JointState, Temperature};
use metrocell_simulation::sim_time::{parse_start_time, DEFAULT_START_TIME};
use metrocell_simulation::{write_bag, BagOptions, BagSummary};
use metrocell_twin::Cell;

const DURATION: f64 = 60.0;

fn cell_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../twin/examples/cells")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, seed: u64) -> BagSummary {
    let cell = Cell::from_path(cell_path("quick_demo.yaml")).unwrap();
    let mut calls = 0;
    let s = write_bag(cell, DURATION, seed, dir, &BagOptions::default(), |p| {
        assert!(p.t <= p.duration);
        calls += 1;
    })
    .unwrap();
    assert!(calls >= 1);
    s
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

fn decode<T: serde::de::DeserializeOwned>(data: &[u8]) -> T {
    assert_eq!(&data[..4], &[0, 1, 0, 0], "encapsulation header");
    rustdds::serialization::from_bytes::<T, byteorder::LittleEndian>(&data[4..])
        .unwrap()
        .0
}

#[test]
fn same_seed_gives_byte_identical_bags_and_counts_follow_the_rates() {
    let root = scratch("determinism");
    let a = write(&root.join("a").join("bag"), 3);
    let b = write(&root.join("b").join("bag"), 3);
    let c = write(&root.join("c").join("bag"), 4);

    // Rates of quick_demo.yaml over 60 s: tracker 10 Hz, thermocouples 1 Hz, machine state 20 Hz, clock 10 Hz.
    let n = &a.messages_per_topic;
    assert_eq!(n["/clock"], 600);
    assert_eq!(n["/tracker/measurements"], 600);
    assert_eq!(n["/temperature/x_left"], 60);
    assert_eq!(n["/temperature/x_right"], 60);
    assert_eq!(n["/machine/joint_states"], 1200);
    assert_eq!(n["/machine/commanded_joint_states"], 1200);
    // 30 s cycles of 6 points, 4 probe directions each; one camera frame per dwell.
    assert!(
        n["/probe/hits"] >= 24 && n["/probe/hits"].is_multiple_of(4),
        "{}",
        n["/probe/hits"]
    );
    assert!(
        n["/camera/camera_info"] >= 6,
        "{}",
        n["/camera/camera_info"]
    );
    assert_eq!(
        n["/camera/image_raw"], n["/camera/camera_info"],
        "one rendered image per camera frame request"
    );
    assert_eq!(a.total_messages, n.values().sum::<u64>());
    assert_eq!(a.metadata.message_count, a.total_messages);

    let fa = files(&a.dir);
    let fb = files(&b.dir);
    let names: Vec<&str> = fa.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["bag_0.mcap", "metadata.yaml"]);
    for ((na, ba), (nb, bb)) in fa.iter().zip(&fb) {
        assert_eq!(na, nb);
        assert!(
            ba == bb,
            "{na} differs between two runs with the same seed ({} vs {} bytes)",
            ba.len(),
            bb.len()
        );
    }
    let fc = files(&c.dir);
    assert_ne!(
        fa[0].1, fc[0].1,
        "a different seed must give a different recording"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn stamps_are_start_plus_t_and_messages_decode() {
    let root = scratch("decode");
    let s = write(&root.join("bag"), 1);
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let reader = BagReader::open(&s.dir).unwrap();
    let tracker = reader.topic("/tracker/measurements").unwrap();
    assert_eq!(tracker.type_name, "metrocell_msgs/msg/TrackerMeasurement");
    assert!(
        tracker.definition.contains("MSG: std_msgs/Header"),
        "full definition with dependencies"
    );
    assert!(
        reader
            .topic("/clock")
            .unwrap()
            .offered_qos_profiles
            .contains("reliability: 2"),
        "clock is best effort"
    );
    assert!(reader
        .topic("/temperature/x_left")
        .unwrap()
        .offered_qos_profiles
        .contains("reliability: 1"));

    let msgs = reader.read_all(&MessageFilter::default()).unwrap();
    assert_eq!(msgs.len() as u64, s.total_messages);
    assert_eq!(msgs.first().unwrap().log_time, start);
    assert!(
        msgs.windows(2).all(|w| w[0].log_time <= w[1].log_time),
        "log-time order"
    );
    let (mut tracker_n, mut temps, mut clocks) = (0, 0, 0);
    for m in &msgs {
        assert_eq!(m.log_time, m.publish_time);
        let stamp_ns = |sec: i32, nanosec: u32| sec as u64 * 1_000_000_000 + nanosec as u64;
        match m.topic.as_str() {
            "/tracker/measurements" => {
                let t: TrackerMeasurement = decode(&m.data);
                assert_eq!(
                    stamp_ns(t.header.stamp.sec, t.header.stamp.nanosec),
                    m.log_time
                );
                // 10 Hz: the k-th measurement is stamped start + k/10 s.
                assert_eq!(m.log_time, start + tracker_n * 100_000_000);
                if t.status == TrackerMeasurement::STATUS_OK {
                    // Tracker at (-1.2, 0.2, 0.6) m, targets inside a 0.4 × 0.3 m travel 0.1 m below the carriage.
                    assert!(t.range > 1.0 && t.range < 2.0, "range {}", t.range);
                    let r = (t.point.x.powi(2) + t.point.y.powi(2) + t.point.z.powi(2)).sqrt();
                    assert!((r - t.range).abs() < 1e-9);
                    assert!(t.covariance[0] > 0.0 && t.covariance[0] < 1e-8);
                    assert!(
                        (t.covariance[1] - t.covariance[3]).abs() <= 1e-12 * t.covariance[0],
                        "symmetric"
                    );
                    assert!(
                        (t.air_humidity - 0.5).abs() < 0.05,
                        "fraction, not %RH: {}",
                        t.air_humidity
                    );
                    assert!(
                        (t.refractive_index - 1.00027).abs() < 2e-5,
                        "{}",
                        t.refractive_index
                    );
                }
                tracker_n += 1;
            }
            "/temperature/x_left" => {
                let t: Temperature = decode(&m.data);
                assert!((t.temperature - 21.0).abs() < 3.0, "{}", t.temperature);
                assert!(
                    (t.variance - 0.02f64.powi(2)).abs() < 1e-12,
                    "{}",
                    t.variance
                );
                assert_eq!(t.header.frame_id, "table");
                temps += 1;
            }
            "/machine/joint_states" => {
                let j: JointState = decode(&m.data);
                assert_eq!(j.name, ["x", "y", "z"]);
                assert!(j.position[0] > -0.01 && j.position[0] < 0.41);
            }
            "/clock" => {
                let c: Clock = decode(&m.data);
                assert_eq!(
                    stamp_ns(c.clock.sec, c.clock.nanosec),
                    start + clocks * 100_000_000
                );
                clocks += 1;
            }
            _ => {}
        }
    }
    assert_eq!((tracker_n, temps, clocks), (600, 60, 600));
    std::fs::remove_dir_all(&root).unwrap();
}
