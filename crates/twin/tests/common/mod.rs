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
    assert_eq!(
        text.matches(from).count(),
        1,
        "edit target `{from}` must occur once"
    );
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
    (
        m,
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt(),
    )
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

/// Every column of the analytic Jacobian `j` of `reading` at `p` (rows of one unit) against
/// 4th-order central differences: |analytic − central| ≤ 1e-6 × (the column's largest entry) +
/// the stencil's rounding. Returns the number of columns checked.
pub fn check_columns(
    what: &str,
    names: &[String],
    p: &[f64],
    j: &nalgebra::DMatrix<f64>,
    reading: impl Fn(&[f64]) -> Vec<f64>,
) -> usize {
    let y = reading(p);
    let y_scale = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    // a column below 1e-9 of the largest entry is zero up to rounding (e.g. the arm's last
    // joint turning the tool point about itself)
    let floor = 1e-9 * j.amax();
    for c in 0..p.len() {
        let col = j.column(c);
        let scale = col.amax().max(floor);
        // a step that moves the reading by ~1e-6 of its size (a few µm of a tracker reading,
        // ~1e-3 px of a pixel), and at most 0.1 % of the parameter
        let step = 1e-6 * y_scale.max(1e-3);
        let mut h = if scale > 0.0 { step / scale } else { step };
        if p[c] != 0.0 {
            h = h.min(1e-3 * p[c].abs());
        }
        let at = |k: f64| {
            let mut q = p.to_vec();
            q[c] += k * h;
            reading(&q)
        };
        let (m2, m1, p1, p2) = (at(-2.0), at(-1.0), at(1.0), at(2.0));
        for r in 0..y.len() {
            let fd = (m2[r] - 8.0 * m1[r] + 8.0 * p1[r] - p2[r]) / (12.0 * h);
            let err = (fd - col[r]).abs();
            // plus the rounding error of the stencil itself (≈ 18·ε·|y|/(12·h))
            let rounding = 4.0 * f64::EPSILON * y_scale / h;
            assert!(
                err <= 1e-6 * scale + rounding,
                "{what}: ∂y{r}/∂{} analytic {} vs central {fd} (column scale {scale})",
                names[c],
                col[r]
            );
        }
    }
    p.len()
}
