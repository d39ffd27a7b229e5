//! `metrocell bag info BAG` and `metrocell bag recover BAG`.

use std::path::PathBuf;

#[derive(clap::Args)]
#[command(
    after_help = "Exit status: 0 for a healthy bag; 1 when it is damaged (the problems are listed with the \
next step, `metrocell bag recover`); 2 when there is no bag to read."
)]
pub struct InfoArgs {
    /// Bag directory (or one .mcap file)
    bag: PathBuf,
}

#[derive(clap::Args)]
#[command(
    after_help = "Keeps every message whose chunk reached the disk intact; at most the messages of the \
last flush interval (recorder parameter flush_interval, default 1 s) are lost."
)]
pub struct RecoverArgs {
    /// Bag directory (or one .mcap file)
    bag: PathBuf,
}

pub fn run_info(args: InfoArgs) -> anyhow::Result<i32> {
    let info = metrocell_bag::info(&args.bag)?;
    print!("{info}");
    Ok(if info.problems.is_empty() { 0 } else { 1 })
}

pub fn run_recover(args: RecoverArgs) -> anyhow::Result<i32> {
    let report = metrocell_bag::recover(&args.bag)?;
    print!("{report}");
    Ok(0)
}
