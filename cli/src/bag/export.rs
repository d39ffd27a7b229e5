//! `metrocell bag export BAG --topics T... --format csv|parquet -o DIR`

use std::path::PathBuf;

#[derive(Clone, Copy, clap::ValueEnum)]
enum Format {
    Csv,
    Parquet,
}

#[derive(clap::Args)]
#[command(
    after_help = "One file per topic (/a/b → a.b.csv or a.b.parquet); columns log_time_ns, publish_time_ns, then \
one per leaf field with dotted names (a topic without messages: the header alone); fixed arrays expand to name.0, name.1, ...\n\
DIR/export.yaml names each file's topic, type and QoS: `metrocell bag import DIR -o BAG` rebuilds the bag from either \
format, every message with its fields and its log and publish times.\n\
CSV: variable arrays are JSON text in one column.\n\
Parquet: typed columns (int/uint of the field's width, float32/float64, UTF-8 strings); variable arrays of \
numbers or strings are LIST columns (pandas: one numpy array per cell); arrays of messages are JSON text.\n\n\
Examples:\n  metrocell bag export run42 --topics /measured_points -o run42_csv\n  \
metrocell bag export run42 --format parquet -o run42_pq   # pandas.read_parquet('run42_pq/measured_points.parquet')"
)]
pub struct ExportArgs {
    /// Bag directory
    bag: PathBuf,
    /// Topics to export (default: all)
    #[arg(long, num_args = 1..)]
    topics: Vec<String>,
    /// Output format
    #[arg(long, value_enum, default_value = "csv")]
    format: Format,
    /// Output directory
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: ExportArgs) -> anyhow::Result<i32> {
    let exported = match a.format {
        Format::Csv => metrocell_bagtools::export::export_csv(&a.bag, &a.topics, &a.output)?,
        Format::Parquet => metrocell_parquet_export::export_parquet(&a.bag, &a.topics, &a.output)?,
    };
    for (topic, e) in exported {
        println!(
            "{topic}: {} rows x {} columns -> {}",
            e.rows,
            e.columns,
            e.path.display()
        );
    }
    Ok(0)
}
