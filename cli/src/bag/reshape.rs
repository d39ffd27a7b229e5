//! `metrocell bag filter` and `metrocell bag merge`.

use std::path::PathBuf;

use metrocell_bag::WriterOptions;
use metrocell_bagtools::{filter_bag, merge_bags, CopyReport, TopicSelection};

#[derive(clap::Args)]
#[command(
    after_help = "Example:\n  metrocell bag filter run42 run42_tracker --topics /tracker/measurements --start 10 --end 70"
)]
pub struct FilterArgs {
    /// Input bag
    input: PathBuf,
    /// Output bag directory (must not exist yet)
    output: PathBuf,
    /// Keep only these topics
    #[arg(long, num_args = 1..)]
    topics: Vec<String>,
    /// Keep only topics matching this regex (whole name)
    #[arg(long, default_value = "")]
    regex: String,
    /// Drop topics matching this regex
    #[arg(long, default_value = "")]
    exclude: String,
    /// Keep messages logged at least this many seconds after the bag's first message
    #[arg(long)]
    start: Option<f64>,
    /// Keep messages logged before this many seconds after the bag's first message
    #[arg(long)]
    end: Option<f64>,
}

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Output bag directory (must not exist yet)
    output: PathBuf,
    /// Input bags
    #[arg(required = true, num_args = 1..)]
    inputs: Vec<PathBuf>,
}

fn print_report(out: &std::path::Path, r: &CopyReport) {
    println!("wrote {} messages to {}", r.total(), out.display());
    for (t, n) in &r.per_topic {
        println!("  {t}: {n}");
    }
}

pub fn run_filter(a: FilterArgs) -> anyhow::Result<i32> {
    let selection = TopicSelection::new(a.topics, &a.regex, &a.exclude)?;
    let input = metrocell_bag::BagReader::open(&a.input)?;
    let start_ns = input.info().start_ns.unwrap_or(0);
    let report = filter_bag(
        &input,
        &a.output,
        &selection,
        super::offset_ns(start_ns, a.start)?,
        super::offset_ns(start_ns, a.end)?,
        WriterOptions::default(),
    )?;
    print_report(&a.output, &report);
    Ok(0)
}

pub fn run_merge(a: MergeArgs) -> anyhow::Result<i32> {
    let inputs: Vec<&std::path::Path> = a.inputs.iter().map(|p| p.as_path()).collect();
    let report = merge_bags(&a.output, &inputs, WriterOptions::default())?;
    print_report(&a.output, &report);
    Ok(0)
}
