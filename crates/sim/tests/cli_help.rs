//! `SimArgs` as the CLI will wire it: the help teaches (examples, topics), durations and
//! compression parse, and bad values are rejected with the offending text.

use clap::{CommandFactory, Parser};
use metrocell_simulation::cli::Compression;
use metrocell_simulation::SimArgs;

#[derive(Parser)]
#[command(name = "metrocell-sim-test")]
struct Cli {
    #[command(flatten)]
    sim: SimArgs,
}

#[test]
fn help_has_examples_and_the_topic_map() {
    let help = Cli::command().render_long_help().to_string();
    for needle in [
        "--cell <FILE>",
        "--duration <D>",
        "--seed <N>",
        "-o, --output <BAG_DIR>",
        "--start-time <RFC3339>",
        "--compression",
        "Examples:",
        "--duration 8h",
        "/tracker/measurements",
        "2026-01-05T06:00:00Z",
        "--ground-tilt <ROLL,PITCH>",
        "/measured_points",
        "/check_points",
        "/imu/<sensor>",
        "--ground-tilt 0,15mrad",
    ] {
        assert!(help.contains(needle), "help lacks {needle:?}:\n{help}");
    }
}

#[test]
fn arguments_parse() {
    let c = Cli::try_parse_from([
        "x",
        "--cell",
        "c.yaml",
        "--duration",
        "90min",
        "-o",
        "out",
        "--compression",
        "lz4",
        "--seed",
        "9",
    ])
    .unwrap();
    assert_eq!(c.sim.duration, Some(5400.0));
    assert_eq!(c.sim.seed, 9);
    assert_eq!(c.sim.compression, Compression::Lz4);
    assert_eq!(c.sim.start_time, "2026-01-05T06:00:00Z");
    let e = Cli::try_parse_from([
        "x",
        "--cell",
        "c.yaml",
        "--duration",
        "8 fortnights",
        "-o",
        "out",
    ])
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("8 fortnights"), "{e}");
}

#[test]
fn a_missing_cell_file_fails_with_its_name() {
    let c = Cli::try_parse_from([
        "x",
        "--cell",
        "/nonexistent/cell.yaml",
        "--duration",
        "1s",
        "-o",
        "/tmp/never",
        "--quiet",
    ])
    .unwrap();
    let e = metrocell_simulation::cli::run_sim(&c.sim)
        .expect_err("a missing cell file is an error")
        .to_string();
    assert!(
        e.contains("/nonexistent/cell.yaml"),
        "the error does not name the file: {e}"
    );
    assert_eq!(metrocell_simulation::run_sim_command(c.sim), 1);
}

/// A shift's cell needs a duration; the ground's tilt is for a stationing program only; a
/// stationing program runs its one pass without one.
#[test]
fn duration_and_ground_tilt_follow_the_program() {
    let cells = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells");
    let demo = cells.join("quick_demo.yaml");
    let out = std::env::temp_dir().join(format!("metrocell_sim_cli_{}", std::process::id()));
    let run = |args: &[&str]| {
        let mut all = vec![
            "x",
            "--quiet",
            "--clock-rate",
            "0",
            "-o",
            out.to_str().unwrap(),
        ];
        all.extend(args);
        metrocell_simulation::cli::run_sim(&Cli::try_parse_from(all).unwrap().sim)
    };
    let e = run(&["--cell", demo.to_str().unwrap()])
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("--duration") && e.contains("is required") && e.contains("quick_demo.yaml"),
        "{e}"
    );
    let e = run(&[
        "--cell",
        demo.to_str().unwrap(),
        "--duration",
        "10s",
        "--ground-tilt",
        "0,15mrad",
    ])
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("--ground-tilt") && e.contains("no stationing program"),
        "{e}"
    );
    let robot = cells.join("mobile_manipulator.yaml");
    let e = run(&["--cell", robot.to_str().unwrap(), "--ground-tilt", "15mrad"])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("ROLL,PITCH"), "{e}");
    // a negative roll parses (not taken for an option)
    let c = Cli::try_parse_from([
        "x",
        "--cell",
        "c.yaml",
        "-o",
        "o",
        "--ground-tilt",
        "-2mrad,1mrad",
    ])
    .unwrap();
    assert_eq!(c.sim.ground_tilt.as_deref(), Some("-2mrad,1mrad"));
    run(&[
        "--cell",
        robot.to_str().unwrap(),
        "--ground-tilt",
        "-2mrad,1mrad",
    ])
    .unwrap();
    let bag = metrocell_bag::BagReader::open(&out).unwrap();
    let info = format!("{:?}", bag.metadata());
    let _ = std::fs::remove_dir_all(&out);
    assert!(
        info.contains("/check_points") && info.contains("/imu/tip"),
        "{info}"
    );
}
