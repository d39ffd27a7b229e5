//! What the DDS tests of the tracker node share: the twin's inputs for the quick tracker cell,
//! in bag order, and waiting until the node is on the wire.
#![allow(dead_code)]

use std::path::Path;
use std::time::{Duration, Instant};

use metrocell_bagtools::BagSource;
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_node::MetrocellNode;
use metrocell_simulation::bag::{write_bag, BagOptions};
use metrocell_twin::Cell;

pub const CELL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/cells/tracker_quick.yaml"
);

pub enum Input {
    Reading(TrackerMeasurement),
    Commanded(JointState),
}

/// The tracker readings and commanded joint states of a bag, in its order.
pub fn inputs(bag: &Path) -> Vec<Input> {
    let mut s = BagSource::open(bag).unwrap();
    s.subscribe::<TrackerMeasurement>("/tracker/measurements")
        .unwrap();
    s.subscribe::<JointState>("/machine/commanded_joint_states")
        .unwrap();
    s.messages()
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            if m.topic == "/tracker/measurements" {
                Input::Reading(m.decode().unwrap())
            } else {
                Input::Commanded(m.decode().unwrap())
            }
        })
        .collect()
}

/// The quick cell, and its twin recorded into `bag` until 5 s after the program's last dwell.
pub fn record_twin(bag: &Path) -> Cell {
    let cell = Cell::from_yaml_str(&std::fs::read_to_string(CELL).unwrap(), CELL).unwrap();
    let program = cell.program.clone();
    let last_dwell_end = program
        .segments
        .iter()
        .filter(|s| s.dwell_point.is_some())
        .map(|s| s.end)
        .fold(0.0, f64::max);
    let options = BagOptions {
        frames: None,
        clock_rate: None,
        ..BagOptions::default()
    };
    let truth = Cell::from_yaml_str(&std::fs::read_to_string(CELL).unwrap(), CELL).unwrap();
    write_bag(
        cell,
        program.start + last_dwell_end + 5.0,
        3,
        bag,
        &options,
        |_| {},
    )
    .unwrap();
    truth
}

/// Wait until the tracker node's outputs are discovered (20 s at most), then a second more for
/// the matching to settle.
pub fn wait_for_tracker(peer: &MetrocellNode) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while !peer
        .discovered_topics()
        .iter()
        .any(|t| t.name.ends_with("tracker/dwells"))
    {
        assert!(Instant::now() < deadline, "tracker node not discovered");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_secs(1));
}
