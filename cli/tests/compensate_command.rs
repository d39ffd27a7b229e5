//! `metrocell compensate gcode|table` end to end on files: a zero model leaves a program as it
//! is but for the header comment, a fitted thermal model needs its temperatures and then moves
//! X by α·x·ΔT, malformed lines are reported with their line numbers, tables are written.

mod common;

use common::metrocell;

fn dir(name: &str) -> std::path::PathBuf {
    common::scratch("compensate", name)
}

const MODEL: &str = "name: fitted\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {x: [0 mm, 400 mm], y: [0 mm, 300 mm], z: [0 mm, 200 mm]}\nterms:\n  - {id: positioning, options: {axis: x, order: 1, travel: [0 mm, 400 mm]}, params: {c0: 0 um, c1: CCC}}\n  - {id: thermal_scale, options: {axis: x, sensors: [{name: x_left, position: 0 m}, {name: x_right, position: 0.4 m}]}, params: {alpha: 10.2e-6 1/K}}\n";
const PROGRAM: &str = "%\n(part 7)\nG21 G90 G17\nG0 X0 Y0 Z10\nG1 X100 Y50 F300 ; first cut\nG2 X150 Y100 I50 J0\nG1 X=1\nG91 G1 X10\nM30\n%\n";

#[test]
fn zero_model_keeps_the_program_and_reports_the_malformed_line() {
    let d = dir("zero");
    std::fs::write(d.join("m.yaml"), MODEL.replace("CCC", "0 um")).unwrap();
    std::fs::write(d.join("in.nc"), PROGRAM).unwrap();
    // α·x·(T − 20 °C) is zero at 20 °C: a zero model
    let (code, out, err) = metrocell(
        &[
            "compensate",
            "gcode",
            "--model",
            "m.yaml",
            "in.nc",
            "-o",
            "out.nc",
            "--temperature",
            "x_left=20",
            "--temperature",
            "x_right=20",
        ],
        &d,
    );
    assert_eq!(
        code, 1,
        "exit 1: a malformed line was passed through\n{out}{err}"
    );
    assert!(out.contains("line 7: malformed"), "{out}");
    let written = std::fs::read_to_string(d.join("out.nc")).unwrap();
    let header: Vec<&str> = written
        .lines()
        .filter(|l| l.starts_with("(metrocell compensate: m.yaml"))
        .collect();
    assert_eq!(header.len(), 1, "{written}");
    assert_eq!(
        written.replacen(&format!("{}\n", header[0]), "", 1),
        PROGRAM,
        "byte for byte but the header comment"
    );
}

#[test]
fn a_thermal_model_needs_its_temperatures_then_moves_x() {
    let d = dir("thermal");
    std::fs::write(d.join("m.yaml"), MODEL.replace("CCC", "0 um")).unwrap();
    std::fs::write(d.join("in.nc"), "G21 G90\nG0 X0 Y0 Z10\nG1 X400 Y0 F300\n").unwrap();
    let (code, _, err) = metrocell(
        &[
            "compensate",
            "gcode",
            "--model",
            "m.yaml",
            "in.nc",
            "-o",
            "out.nc",
        ],
        &d,
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("x_left") && err.contains("--temperature NAME=°C"),
        "{err}"
    );
    let (code, out, err) = metrocell(
        &[
            "compensate",
            "gcode",
            "--model",
            "m.yaml",
            "in.nc",
            "-o",
            "out.nc",
            "--temperature",
            "x_left=22",
            "--temperature",
            "x_right=22",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    // e_x(400 mm) = 10.2e-6 · 0.4 m · 2 K = 8.16 µm; C = T − e(C) ≈ 399.99184 mm
    let written = std::fs::read_to_string(d.join("out.nc")).unwrap();
    assert!(written.contains("G1 X399.9918 F300"), "{written}");
}

#[test]
fn tables_are_written_per_axis_with_squareness() {
    let d = dir("table");
    std::fs::write(d.join("m.yaml"), MODEL.replace("CCC", "10 um")).unwrap();
    let (code, out, err) = metrocell(
        &[
            "compensate",
            "table",
            "--model",
            "m.yaml",
            "-o",
            "tab",
            "--step",
            "100",
            "--temperature",
            "x_left=20",
            "--temperature",
            "x_right=20",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    let x = std::fs::read_to_string(d.join("tab/axis_x.csv")).unwrap();
    assert!(x.contains("position_mm,pitch_um,straightness_y_um,straightness_z_um,reversal_um\n0.000,-10.000,0.000,0.000,0.000\n100.000,-5.000,"), "{x}");
    assert!(x.contains("\n400.000,10.000,0.000,0.000,0.000\n"), "{x}");
    assert_eq!(
        std::fs::read_to_string(d.join("tab/axis_z.csv"))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .count(),
        4
    );
    assert!(std::fs::read_to_string(d.join("tab/squareness.csv"))
        .unwrap()
        .contains("xy,0.000\n"));
    assert!(out.contains("pitch error span 20.00 µm"), "{out}");
}

/// A model with a lagged column growth (as `diagnose` writes it): 4 µm/K along +z, 20 min behind
/// the `column` sensor.
const LAGGED: &str = "name: lagged\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {x: [0 mm, 400 mm], y: [0 mm, 300 mm], z: [0 mm, 200 mm]}\nterms:\n  - id: thermal_growth\n    options: {direction: [0, 0, 1], lag: true, sensor: column}\n    params: {coefficient: 4 um/K, time_constant: 20 min}\n";

/// A recording whose `column` sensor ramps 2 K/h from 20 °C, without noise.
const RAMP: &str = "name: ramp\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {x: [0 mm, 400 mm], y: [0 mm, 300 mm], z: [0 mm, 200 mm]}\nsensors:\n  thermocouples:\n    - {name: column, location: ambient, noise: 0 K, rate: 1 Hz}\nenvironment:\n  ambient: {mean: 20 degC, drift: 2 K/h}\n  air: {pressure: 101.3 kPa, humidity: 45}\nprogram:\n  points: [[100 mm, 100 mm, 100 mm]]\n  feed_rate: 100 mm/s\n  dwell: 10 s\n";

fn pitch_at_first_row(csv: &str) -> f64 {
    let row = csv
        .lines()
        .find(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .unwrap();
    row.split(',').nth(1).unwrap().parse().unwrap()
}

/// Issue 32 item 3: `compensate` asked a lagged `thermal_growth` for `temperature_history[column]`
/// and offered no way to give it.
#[test]
fn a_lagged_growth_takes_a_recorded_history_or_a_stated_steady_state() {
    let d = dir("lagged");
    std::fs::write(d.join("m.yaml"), LAGGED).unwrap();
    // no temperature at all: the error says both ways
    let (code, _, err) = metrocell(
        &["compensate", "table", "--model", "m.yaml", "-o", "t0"],
        &d,
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("lags temperature sensor `column`")
            && err.contains("--temperatures-from BAG")
            && err.contains("--temperature column=°C"),
        "{err}"
    );
    // a steady state at 22 °C: the structure has settled there, 4 µm/K · 2 K = 8 µm along z; said
    let (code, out, err) = metrocell(
        &[
            "compensate",
            "table",
            "--model",
            "m.yaml",
            "-o",
            "t1",
            "--step",
            "50",
            "--temperature",
            "column=22",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains(
            "steady state assumed: thermal_growth[column] lags sensor `column` by τ = 20.0 min"
        ),
        "{out}"
    );
    let z = std::fs::read_to_string(d.join("t1/axis_z.csv")).unwrap();
    assert!(
        z.starts_with("# steady state assumed"),
        "the table says it too:\n{z}"
    );
    assert!((pitch_at_first_row(&z) - 8.0).abs() < 1e-3, "{z}");
    // from a recording: a 2 K/h ramp seen through a 20 min lag at 1 h is
    // 22 − (2 K/h · 20 min)(1 − e^(−3)) = 21.3665 °C, so 5.466 µm
    std::fs::write(d.join("ramp.yaml"), RAMP).unwrap();
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            "ramp.yaml",
            "--duration",
            "90min",
            "-o",
            "ramp_bag",
            "--quiet",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = metrocell(
        &[
            "compensate",
            "table",
            "--model",
            "m.yaml",
            "-o",
            "t2",
            "--step",
            "50",
            "--temperatures-from",
            "ramp_bag",
            "--at-time",
            "1h",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("temperatures from ramp_bag at 3600 s after its first temperature sample (1.00 h): column 22.00 °C"), "{out}");
    assert!(
        out.contains("its structure is at 21.37 °C") && !out.contains("steady state"),
        "{out}"
    );
    let z = std::fs::read_to_string(d.join("t2/axis_z.csv")).unwrap();
    assert!((pitch_at_first_row(&z) - 5.466).abs() < 0.005, "{z}");
    // the G-code command takes the same options
    std::fs::write(d.join("in.nc"), "G21 G90\nG1 X100 Y100 Z100 F300\n").unwrap();
    let (code, out, err) = metrocell(
        &[
            "compensate",
            "gcode",
            "--model",
            "m.yaml",
            "in.nc",
            "-o",
            "out.nc",
            "--temperatures-from",
            "ramp_bag",
            "--at-time",
            "1h",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        std::fs::read_to_string(d.join("out.nc"))
            .unwrap()
            .contains("Z99.9945"),
        "C = T − e: 100 mm − 5.466 µm"
    );
    // a time outside the recording, or without one, is named
    let (code, _, err) = metrocell(
        &[
            "compensate",
            "table",
            "--model",
            "m.yaml",
            "-o",
            "t3",
            "--temperatures-from",
            "ramp_bag",
            "--at-time",
            "3h",
        ],
        &d,
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("--at-time `3h`") && err.contains("give a time in it"),
        "{err}"
    );
    let (code, _, err) = metrocell(
        &[
            "compensate",
            "table",
            "--model",
            "m.yaml",
            "-o",
            "t4",
            "--temperature",
            "column=22",
            "--at-time",
            "1h",
        ],
        &d,
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("--at-time") && err.contains("--temperatures-from BAG"),
        "{err}"
    );
}

/// Issue 32: a sensor the model does not read, a reference outside the travel and a zero step
/// are refused in the user's units, and an arm's tables are refused without speaking of G-code.
#[test]
fn conditions_the_model_cannot_use_are_refused() {
    let d = dir("refused");
    std::fs::write(d.join("m.yaml"), MODEL.replace("CCC", "10 um")).unwrap();
    let temps = ["--temperature", "x_left=20", "--temperature", "x_right=20"];
    let run = |extra: &[&str]| {
        let mut args = vec!["compensate", "table", "--model", "m.yaml", "-o", "tab"];
        args.extend_from_slice(&temps);
        args.extend_from_slice(extra);
        metrocell(&args, &d)
    };
    let (code, _, err) = run(&["--temperature", "bogus=99"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("no sensor `bogus`") && err.contains("x_left, x_right"),
        "{err}"
    );
    let (code, _, err) = run(&["--at", "5000,0,0"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--at 5000,0,0: outside the machine's travel")
            && err.contains("X 0.000…400.000 mm"),
        "{err}"
    );
    let (code, _, err) = run(&["--step", "0"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--step must be > 0 mm, got 0 mm") && !err.contains(" m\n"),
        "{err}"
    );
    std::fs::write(d.join("in.nc"), "G21 G90\nG1 X10 F100\n").unwrap();
    let (code, _, err) = metrocell(
        &[
            "compensate",
            "gcode",
            "--model",
            "m.yaml",
            "in.nc",
            "-o",
            "out.nc",
            "--temperature",
            "x_left=20",
            "--temperature",
            "x_right=20",
            "--temperature",
            "bogus=99",
        ],
        &d,
    );
    assert!(code == 2 && err.contains("no sensor `bogus`"), "{err}");

    let arm = format!(
        "{}/../launch-configs/cells/serial_arm_ur5.yaml",
        env!("CARGO_MANIFEST_DIR")
    );
    let (code, _, err) = metrocell(
        &["compensate", "table", "--model", &arm, "-o", "arm_tab"],
        &d,
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("compensation tables are per linear axis")
            && err.contains("serial_arm")
            && !err.contains("G-code")
            && !err.contains("--temperature"),
        "{err}"
    );
}
