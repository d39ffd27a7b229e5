//! `metrocell bag ...`: record, inspect, repair, replay, cut, merge, export and import rosbag2 MCAP bags.
//!
//! The library work lives in `metrocell-bag` (reading/writing/recovery) and
//! `metrocell-bagtools` (filter/merge/export/import/playback timing); these files parse
//! arguments, print, and own the DDS endpoints of `bag play` (`bag record` runs the recorder node's library).

mod export;
mod import;
mod info;
mod keyboard;
mod play;
mod record;
mod reshape;

#[derive(clap::Subcommand)]
pub enum BagCommand {
    /// Summarise a bag: files, topics, types, counts, rates, duration, time range, size
    Info(info::InfoArgs),
    /// Rebuild a valid bag after a crash (kill -9, power loss, truncated file)
    Recover(info::RecoverArgs),
    /// Record DDS topics into a new bag (ros2 bag record's options; the recorder node in-process)
    Record(record::RecordArgs),
    /// Publish a bag's messages over DDS with their original timing
    Play(play::PlayArgs),
    /// Copy chosen topics and a time window into a new bag
    Filter(reshape::FilterArgs),
    /// Merge bags into a new bag, interleaved by log time
    Merge(reshape::MergeArgs),
    /// Export topics to CSV or Parquet, one file per topic and one column per field
    Export(export::ExportArgs),
    /// Rebuild a bag from `bag export`'s files, or import a point-measurement CSV (or a mapped tracker-software export)
    Import(import::ImportArgs),
}

pub fn run(command: BagCommand) -> i32 {
    let result = match command {
        BagCommand::Info(a) => info::run_info(a),
        BagCommand::Recover(a) => info::run_recover(a),
        BagCommand::Record(a) => record::run(a),
        BagCommand::Play(a) => play::run(a),
        BagCommand::Filter(a) => reshape::run_filter(a),
        BagCommand::Merge(a) => reshape::run_merge(a),
        BagCommand::Export(a) => export::run(a),
        BagCommand::Import(a) => import::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("metrocell bag: {e:#}");
            2
        }
    }
}

/// Seconds (relative to the bag's first message) → absolute ns, given the bag's start.
fn offset_ns(bag_start_ns: u64, seconds: Option<f64>) -> anyhow::Result<Option<u64>> {
    match seconds {
        None => Ok(None),
        Some(s) if s.is_finite() && s >= 0.0 => Ok(Some(bag_start_ns + (s * 1e9).round() as u64)),
        Some(s) => anyhow::bail!("time offset {s} s must be a non-negative number of seconds"),
    }
}
