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
    for needle in ["--cell <FILE>", "--duration <D>", "--seed <N>", "-o, --output <BAG_DIR>", "--start-time <RFC3339>", "--compression", "Examples:", "--duration 8h", "/tracker/measurements", "2026-01-05T06:00:00Z"] {
        assert!(help.contains(needle), "help lacks {needle:?}:\n{help}");
    }
}

#[test]
fn arguments_parse() {
    let c = Cli::try_parse_from(["x", "--cell", "c.yaml", "--duration", "90min", "-o", "out", "--compression", "lz4", "--seed", "9"]).unwrap();
    assert_eq!(c.sim.duration, 5400.0);
    assert_eq!(c.sim.seed, 9);
    assert_eq!(c.sim.compression, Compression::Lz4);
    assert_eq!(c.sim.start_time, "2026-01-05T06:00:00Z");
    let e = Cli::try_parse_from(["x", "--cell", "c.yaml", "--duration", "8 fortnights", "-o", "out"]).err().unwrap().to_string();
    assert!(e.contains("8 fortnights"), "{e}");
}

#[test]
fn a_missing_cell_file_fails_with_its_name() {
    let c = Cli::try_parse_from(["x", "--cell", "/nonexistent/cell.yaml", "--duration", "1s", "-o", "/tmp/never", "--quiet"]).unwrap();
    let e = metrocell_simulation::cli::run_sim(&c.sim).err().expect("a missing cell file is an error").to_string();
    assert!(e.contains("/nonexistent/cell.yaml"), "the error does not name the file: {e}");
    assert_eq!(metrocell_simulation::run_sim_command(c.sim), 1);
}
