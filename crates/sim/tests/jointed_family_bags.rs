//! write_bag for the five_axis and serial_arm example cells: the joint-state topics carry the
//! family's joint names and as many values, and the counts follow the cell's rates.

use std::path::{Path, PathBuf};

use metrocell_bag::{BagReader, MessageFilter};
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image, JointState};
use metrocell_simulation::{write_bag, BagOptions};
use metrocell_twin::Cell;

const DURATION: f64 = 20.0;

fn cell_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../twin/examples/cells")
        .join(name)
}

fn decode<T: serde::de::DeserializeOwned>(data: &[u8]) -> T {
    assert_eq!(&data[..4], &[0, 1, 0, 0], "encapsulation header");
    rustdds::serialization::from_bytes::<T, byteorder::LittleEndian>(&data[4..])
        .unwrap()
        .0
}

#[test]
fn bags_of_the_jointed_examples_carry_their_joint_names() {
    let root =
        std::env::temp_dir().join(format!("metrocell-sim-test-{}-jointed", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let arm_names: Vec<String> = (1..=6).map(|i| format!("joint_{i}")).collect();
    let five_names: Vec<String> = ["x", "y", "z", "b", "c"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for (file, names) in [
        ("five_axis_table.yaml", five_names),
        ("serial_arm_ur5.yaml", arm_names),
    ] {
        let cell = Cell::from_path(cell_path(file)).unwrap();
        let dir = root.join(file.trim_end_matches(".yaml")).join("bag");
        let s = write_bag(cell, DURATION, 9, &dir, &BagOptions::default(), |_| {}).unwrap();
        let n = &s.messages_per_topic;
        // 20 Hz machine state, 10 Hz tracker, 1 Hz thermocouples over 20 s
        assert_eq!(n["/machine/joint_states"], 400, "{file}");
        assert_eq!(n["/machine/commanded_joint_states"], 400, "{file}");
        assert_eq!(n["/tracker/measurements"], 200, "{file}");
        assert_eq!(
            n.keys()
                .filter(|k| k.starts_with("/temperature/"))
                .map(|k| n[k])
                .sum::<u64>(),
            40,
            "{file}"
        );
        let reader = BagReader::open(&s.dir).unwrap();
        let msgs = reader.read_all(&MessageFilter::default()).unwrap();
        assert_eq!(msgs.len() as u64, s.total_messages);
        let (mut states, mut differs, mut tracker_ok, mut camera_infos) = (0, false, 0, 0);
        let mut commanded: Vec<Vec<f64>> = Vec::new();
        for m in &msgs {
            match m.topic.as_str() {
                "/machine/joint_states" => {
                    let j: JointState = decode(&m.data);
                    assert_eq!(j.name, names, "{file}");
                    assert_eq!(j.position.len(), names.len());
                    assert!(j.position.iter().all(|v| v.is_finite()));
                    states += 1;
                }
                "/machine/commanded_joint_states" => {
                    let j: JointState = decode(&m.data);
                    assert_eq!(j.name, names, "{file}");
                    commanded.push(j.position);
                }
                "/camera/camera_info" => {
                    // the five-axis example states its lens; the bag carries it, not the default
                    let c: CameraInfo = decode(&m.data);
                    assert_eq!((c.width, c.height), (1280, 1024));
                    assert_eq!(
                        (c.k[0], c.k[2], c.k[4], c.k[5]),
                        (1600.0, 639.5, 1600.0, 511.5)
                    );
                    assert_eq!(c.d, [-0.08, 0.02, 0.0, 0.0, 0.0]);
                    camera_infos += 1;
                }
                "/camera/image_raw" => {
                    let i: Image = decode(&m.data);
                    assert_eq!((i.width, i.height, i.data.len()), (1280, 1024, 1280 * 1024));
                }
                "/tracker/measurements" => {
                    let t: TrackerMeasurement = decode(&m.data);
                    if t.status == TrackerMeasurement::STATUS_OK {
                        assert!(t.range > 0.5 && t.range < 5.0, "{file}: range {}", t.range);
                        tracker_ok += 1;
                    }
                }
                _ => {}
            }
        }
        assert_eq!(states, 400);
        assert_eq!(tracker_ok, 200, "{file}: no beam breaks configured");
        for w in commanded.windows(2) {
            differs |= w[0] != w[1];
        }
        assert!(differs, "{file}: the commanded joints move");
        if file.starts_with("five") {
            assert!(
                camera_infos >= 1 && n["/camera/image_raw"] == n["/camera/camera_info"],
                "{file}: {n:?}"
            );
        }
    }
    std::fs::remove_dir_all(&root).unwrap();
}
