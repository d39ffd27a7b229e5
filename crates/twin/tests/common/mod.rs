#![allow(dead_code)]
//! Helpers shared by the twin's integration tests.

use metrocell_twin::cell_file::CellFile;
use metrocell_twin::quantity::Quantity;
use metrocell_twin::Cell;

pub fn cell_path(name: &str) -> String {
    format!("{}/examples/cells/{name}", env!("CARGO_MANIFEST_DIR"))
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
