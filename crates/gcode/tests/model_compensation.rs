//! A fitted model file as the compensator's error field: a zero model leaves a program byte for
//! byte but the header comment; a real model's commanded points reach the programmed ones; a
//! thermal term without its temperature is named; the controller tables tabulate the model.

use metrocell_gcode::controller_table::{axis_csv, axis_tables, squareness, squareness_csv};
use metrocell_gcode::{compensate_program, CompensationOptions, ErrorField, ModelErrorField};
use metrocell_physics::Signals;
use metrocell_twin::CellModel;
use nalgebra::Vector3;
use std::path::Path;

const BASE: &str = "name: fitted\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}\n  tool_offset: [0 mm, 0 mm, -150 mm]\nterms:\n";

fn model(terms: &str) -> CellModel {
    CellModel::from_yaml_str_in(&format!("{BASE}{terms}"), "fitted.yaml", Path::new(".")).unwrap()
}

const PROGRAM: &str = "%\n(pocket, metrocell test)\nG21 G90 G17\nG0 X10 Y10 Z5\nG1 Z-1 F300 ; plunge\nG1 X110 Y10\nG2 X110 Y60 I0 J25\nG3 X60 Y110 R50\nG91 G1 X-20 Y-20\nG90\nG1 X=5 Y5\nG20 G1 X2.0 Y1.0\nM30\n%\n";

#[test]
fn a_zero_model_changes_only_the_header_comment_and_passes_malformed_lines_through() {
    let m = model("  - {id: positioning, options: {axis: x, order: 2, travel: [0 mm, 800 mm]}, params: {c0: 0 um, c1: 0 um, c2: 0 um}}\n  - {id: backlash, options: {axis: y}, params: {reversal: 0 um}}\n");
    let fm = m.forward_model().unwrap();
    let field = ModelErrorField::new(&fm, fm.params(), Signals::default()).unwrap();
    let (out, report) = compensate_program(PROGRAM, &field, &CompensationOptions::default());
    let (a, b): (Vec<&str>, Vec<&str>) = (PROGRAM.lines().collect(), out.lines().collect());
    assert_eq!(b.len(), a.len() + 1, "{out}");
    let extra: Vec<&&str> = b.iter().filter(|l| !a.contains(l)).collect();
    assert_eq!(extra.len(), 1, "only the header comment is new: {extra:?}");
    assert!(
        extra[0].starts_with('(') || extra[0].starts_with(';'),
        "{extra:?}"
    );
    let without: Vec<&str> = b.iter().copied().filter(|l| l != extra[0]).collect();
    assert_eq!(
        without, a,
        "every input line kept byte for byte and in order"
    );
    assert_eq!(
        report.malformed.iter().map(|i| i.line).collect::<Vec<_>>(),
        [11],
        "{:?}",
        report.malformed
    );
}

#[test]
fn commanded_points_reach_the_programmed_ones_through_the_model() {
    let m = model("  - {id: positioning, options: {axis: x, order: 2, travel: [0 mm, 800 mm]}, params: {c0: 2 um, c1: 12 um, c2: 0 um}}\n  - {id: squareness, options: {pair: xy}, params: {s: 40 urad}}\n  - {id: backlash, options: {axis: x}, params: {reversal: 9 um}}\n");
    let fm = m.forward_model().unwrap();
    let field = ModelErrorField::new(&fm, fm.params(), Signals::default()).unwrap();
    let (out, report) = compensate_program(
        "G21 G90\nG0 X0 Y0 Z50\nG1 X100 Y200 Z50 F500\nG1 X50 Y200\n",
        &field,
        &CompensationOptions::default(),
    );
    // a linear field does not bend a straight move; the reversal of X before the last move is
    // taken up by one added move
    assert_eq!((report.changed_lines, report.added_lines), (3, 1), "{out}");
    // the controller's position after each motion line (modal coordinates, mm)
    let mut at = Vector3::zeros();
    let mut positions = vec![];
    for line in out
        .lines()
        .filter(|l| l.starts_with("G0") || l.starts_with("G1"))
    {
        for w in line.split_whitespace() {
            let k = "XYZ".find(&w[..1]);
            if let (Some(k), Ok(v)) = (k, w[1..].parse::<f64>()) {
                at[k] = v * 1e-3;
            }
        }
        positions.push(at);
    }
    // after the move, after the take-up (now approaching X from +X: approach −1), at the end:
    // each time the machine is where the program wants it
    let expected = [
        (1, Vector3::new(0.1, 0.2, 0.05), [1.0, 1.0, 1.0]),
        (2, Vector3::new(0.1, 0.2, 0.05), [-1.0, 1.0, 1.0]),
        (3, Vector3::new(0.05, 0.2, 0.05), [-1.0, 1.0, 1.0]),
    ];
    for (i, t, approach) in expected {
        let c = positions[i];
        let reached = c + field.error(&c, &approach).unwrap();
        assert!((reached - t).norm() < 1e-7, "motion line {i}: reaches {reached:?} for {t:?} (within the output's 4 decimals of mm)\n{out}");
    }
    assert!(report.max_correction_m > 5e-6);
}

#[test]
fn a_thermal_term_needs_its_temperature() {
    let m = model("  - {id: thermal_scale, options: {axis: x, sensors: [{name: x_left, position: 0 m}, {name: x_right, position: 0.8 m}]}, params: {alpha: 10.2e-6 1/K}}\n");
    let fm = m.forward_model().unwrap();
    let e = ModelErrorField::new(&fm, fm.params(), Signals::default())
        .err()
        .expect("no temperatures")
        .to_string();
    assert!(e.contains("x_left") || e.contains("x_right"), "{e}");
    let mut s = Signals::default();
    s.temperatures.insert("x_left".into(), 22.0);
    s.temperatures.insert("x_right".into(), 22.0);
    let field = ModelErrorField::new(&fm, fm.params(), s).unwrap();
    let e = field
        .error(&Vector3::new(0.5, 0.0, 0.0), &[1.0; 3])
        .unwrap();
    assert!(
        (e.x - 10.2e-6 * 0.5 * 2.0).abs() < 1e-12,
        "α·x·ΔT = {}",
        e.x
    );
}

#[test]
fn controller_tables_tabulate_the_model() {
    let m = model("  - {id: positioning, options: {axis: x, order: 1, travel: [0 mm, 800 mm]}, params: {c0: 0 um, c1: 12 um}}\n  - {id: squareness, options: {pair: xy}, params: {s: 20 urad}}\n  - {id: squareness, options: {pair: yz}, params: {s: -15 urad}}\n  - {id: backlash, options: {axis: y}, params: {reversal: 9 um}}\n");
    let fm = m.forward_model().unwrap();
    let field = ModelErrorField::new(&fm, fm.params(), Signals::default()).unwrap();
    let region = field.calibrated_region().unwrap();
    let reference = Vector3::new(0.4, 0.25, 0.2);
    let tables = axis_tables(&field, &region, &reference, 0.05).unwrap();
    assert_eq!(tables[0].positions.len(), 17);
    assert_eq!(tables[2].positions.last(), Some(&0.4));
    // pitch of X: the Legendre series c1·(2x/L − 1): −12 µm at 0, +12 µm at 800 mm, plus the
    // squareness's −y·s = −5 µm at the reference y = 250 mm
    assert!(
        (tables[0].errors[0].x + 17e-6).abs() < 1e-12
            && (tables[0].errors[16].x - 7e-6).abs() < 1e-12,
        "{:?}",
        tables[0].errors
    );
    // reversal of Y only
    assert!(
        tables[1]
            .reversal
            .iter()
            .all(|r| (r.abs() - 9e-6).abs() < 1e-12),
        "{:?}",
        tables[1].reversal
    );
    assert!(tables[0]
        .reversal
        .iter()
        .chain(&tables[2].reversal)
        .all(|r| r.abs() < 1e-15));
    let sq = squareness(&tables);
    assert_eq!(
        sq.iter().map(|(p, _)| p.as_str()).collect::<Vec<_>>(),
        ["xy", "xz", "yz"]
    );
    assert!(
        (sq[0].1 - 20e-6).abs() < 1e-12 && sq[1].1.abs() < 1e-12 && (sq[2].1 + 15e-6).abs() < 1e-12,
        "{sq:?}"
    );
    let csv = axis_csv(&tables[0], "fitted.yaml");
    assert!(
        csv.contains(
            "position_mm,pitch_um,straightness_y_um,straightness_z_um,reversal_um\n0.000,-17.000,"
        ),
        "{csv}"
    );
    assert_eq!(csv.lines().filter(|l| !l.starts_with('#')).count(), 18);
    assert!(squareness_csv(&sq, "fitted.yaml").contains("xy,20.000\n"));
}

/// Issue 32: the take-up move of a reversal is a line of its own, without the programmed line's
/// N number or comment; the programmed line keeps both (and its feed is the take-up's too).
#[test]
fn a_take_up_move_leaves_the_line_its_number_and_comment() {
    let m = model("  - {id: backlash, options: {axis: x}, params: {reversal: 9 um}}\n");
    let fm = m.forward_model().unwrap();
    let field = ModelErrorField::new(&fm, fm.params(), Signals::default()).unwrap();
    let (out, report) = compensate_program(
        "G21 G90\nG0 X0 Y0 Z50\nN10 G1 X100 Y200 F500 (out)\nN20 G1 X50 F250 ; back along X\n",
        &field,
        &CompensationOptions::default(),
    );
    assert_eq!(report.added_lines, 1, "one take-up move\n{out}");
    let lines: Vec<&str> = out.lines().collect();
    let n20 = lines
        .iter()
        .position(|l| l.starts_with("N20"))
        .unwrap_or_else(|| panic!("N20 kept at the start of its line\n{out}"));
    assert!(
        lines[n20].starts_with("N20 G1 X") && lines[n20].ends_with("F250 ; back along X"),
        "{}",
        lines[n20]
    );
    let take_up = lines[n20 - 1];
    assert!(
        take_up.starts_with("G1 X") && take_up.ends_with(" F250"),
        "the take-up: G1, its X, the line's feed: {take_up}"
    );
    assert!(
        !take_up.contains('N') && !take_up.contains(';') && !take_up.contains('('),
        "{take_up}"
    );
    assert_eq!(
        out.lines().filter(|l| l.contains("N20")).count(),
        1,
        "{out}"
    );
}
