//! `metrocell bag export BAG --topics T... --format csv -o DIR`

use std::path::PathBuf;

#[derive(Clone, Copy, clap::ValueEnum)]
enum Format {
    Csv,
    Parquet,
}

#[derive(clap::Args)]
#[command(after_help = "One file per topic (/a/b → a.b.csv); columns log_time_ns, publish_time_ns, then one per leaf \
field with dotted names; fixed arrays expand to name.0, name.1, ...; variable arrays are JSON text in one column.\n\n\
Example:\n  metrocell bag export run42 --topics /measured_points -o run42_csv")]
pub struct ExportArgs {
    /// Bag directory
    bag: PathBuf,
    /// Topics to export (default: all)
    #[arg(long, num_args = 1..)]
    topics: Vec<String>,
    /// Output format (Parquet is not built in; use CSV)
    #[arg(long, value_enum, default_value = "csv")]
    format: Format,
    /// Output directory
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: ExportArgs) -> anyhow::Result<i32> {
    if let Format::Parquet = a.format {
        anyhow::bail!("Parquet export is not built into metrocell (the arrow/parquet crates cost too much build time); \
                       export CSV and convert, e.g. with pandas: pd.read_csv(f).to_parquet(...)");
    }
    for (topic, e) in metrocell_bagtools::export::export_csv(&a.bag, &a.topics, &a.output)? {
        println!("{topic}: {} rows x {} columns -> {}", e.rows, e.columns, e.path.display());
    }
    Ok(0)
}
