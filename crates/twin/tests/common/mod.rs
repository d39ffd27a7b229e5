#![allow(dead_code)]
//! Helpers shared by the twin's integration tests.

use metrocell_twin::cell_file::CellFile;
use metrocell_twin::quantity::Quantity;
use metrocell_twin::Cell;

pub fn cell_path(name: &str) -> String {
    format!("{}/examples/cells/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Example cell `file` with `from` replaced by `to` (which must occur exactly once).
pub fn edited_example(file: &str, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(cell_path(file)).unwrap();
    assert_eq!(text.matches(from).count(), 1, "edit target `{from}` must occur once");
    text.replace(from, to)
}

/// The error a cell text must give (panics if the cell is accepted).
pub fn error_of(text: &str) -> String {
    match Cell::from_yaml_str(text, "bad.yaml") {
        Ok(_) => panic!("cell accepted"),
        Err(e) => {
            println!("{e}");
            e.to_string()
        }
    }
}

pub fn assert_mentions(msg: &str, needles: &[&str]) {
    for n in needles {
        assert!(msg.contains(n), "message lacks `{n}`: {msg}");
    }
}

/// The parsed (not yet validated) example file, for tests to modify.
pub fn example_file(name: &str) -> CellFile {
    let text = std::fs::read_to_string(cell_path(name)).expect("example cell exists");
    serde_yaml::from_str(&text).expect("example cell parses")
}

pub fn validate(f: &CellFile) -> Cell {
    Cell::from_file(f).unwrap_or_else(|e| panic!("cell invalid: {e}"))
}

pub fn q(text: &str) -> Quantity {
    Quantity::Text(text.into())
}

/// A quiet tracker: no warm-up, no station error, no turbulence, no breaks.
pub fn quiet_tracker(f: &mut CellFile) {
    let t = f.sensors.tracker.as_mut().expect("tracker");
    t.warmup = None;
    t.station = None;
    t.turbulence.clear();
    t.beam_breaks = None;
}

pub fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt())
}

/// A planar two-link URDF arm (shoulder at 0.3 m height, links 0.5 m and 0.4 m, fixed flange).
pub const TWO_LINK_URDF: &str = r#"<robot name="two_link">
  <link name="base"/><link name="upper"/><link name="fore"/><link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="fore"/><child link="tip"/><origin xyz="0.4 0 0" rpy="0 0 0"/></joint>
</robot>"#;
