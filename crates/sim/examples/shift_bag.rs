//! Benchmark and demo: the `metrocell sim` command as a stand-alone program (the same
//! `SimArgs` the CLI flattens in), e.g. the 8-hour shift:
//!
//!   cargo run --release -p metrocell-simulation --example shift_bag -- \
//!       --cell crates/twin/examples/cells/xfyz_shift.yaml --duration 8h -o /tmp/shift_bag
//!
//! Wrap it in `/usr/bin/time -v` for the peak memory.

use clap::Parser;
use metrocell_simulation::{run_sim_command, SimArgs};

#[derive(Parser)]
#[command(name = "shift_bag")]
struct Cli {
    #[command(flatten)]
    sim: SimArgs,
}

fn main() {
    std::process::exit(run_sim_command(Cli::parse().sim));
}
