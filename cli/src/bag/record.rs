//! `metrocell bag record`: `ros2 bag record`'s options, running the recorder node's code
//! (`metrocell_recorder_node::record`) in this process. The options become the node's parameter
//! values, so `--ros-args` given after `--` can still override them, as for the node binary.

use std::path::PathBuf;

use metrocell_node::params::set_default as set;
use metrocell_node::MetrocellNode;
use metrocell_recorder_node::{parameters, record, RecorderSettings};

#[derive(clap::Args)]
#[command(after_help = "What is recorded:\n  \
Every selected topic discovery shows, re-scanned every second, so publishers that start later are\n  \
recorded too. Payloads are stored byte for byte (raw CDR); a type metrocell does not know is recorded\n  \
all the same, without a definition. A topic is read reliably when all its publishers are reliable\n  \
(nothing is lost on the wire), best effort otherwise, transient-local when all are latched.\n  \
Ctrl-C (SIGINT) or SIGTERM finishes the bag; the last line says how many messages were recorded and,\n  \
per topic, any that are missing and why (sequence gaps, published before the recorder subscribed).\n\n\
Runs DDS: on a shared network start it inside tests/isolated.\n\n\
Examples:\n  \
metrocell bag record -a -o run42                      # everything\n  \
metrocell bag record /tracker/measurements /clock     # two topics\n  \
metrocell bag record -e '/temperature/.*' -x '/temperature/debug.*' --compression-format lz4\n  \
metrocell bag record -a -b 100000000 -d 600           # a new .mcap file every 100 MB or 10 min\n  \
metrocell bag record -a --qos-profile-overrides-path qos.yaml -- --ros-args -r __node:=rec2\n\n\
QoS overrides file (rosbag2's format), per topic:\n  \
/tracker/measurements: {reliability: reliable, durability: volatile, history: keep_last, depth: 5000}")]
pub struct RecordArgs {
    /// Topics to record (full names); or use -a / -e
    topics: Vec<String>,
    /// Record every topic
    #[arg(short = 'a', long = "all", alias = "all-topics")]
    all: bool,
    /// Bag directory to create (default: bag_<UTC date-time>)
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
    /// Record topics matching this regular expression (whole name), e.g. '/camera/.*'
    #[arg(short = 'e', long)]
    regex: Option<String>,
    /// Do not record topics matching this regular expression (whole name)
    #[arg(short = 'x', long, alias = "exclude-regex")]
    exclude: Option<String>,
    /// Start a new .mcap file after this many bytes (0: never)
    #[arg(short = 'b', long, default_value_t = 0)]
    max_bag_size: u64,
    /// Start a new .mcap file after this many seconds (0: never)
    #[arg(short = 'd', long, default_value_t = 0.0)]
    max_bag_duration: f64,
    /// Chunk compression of the MCAP files: zstd, lz4 or none
    #[arg(long, default_value = "zstd", value_parser = ["zstd", "lz4", "none"])]
    compression_format: String,
    /// YAML file of per-topic reader QoS, as for ros2 bag record
    #[arg(long)]
    qos_profile_overrides_path: Option<PathBuf>,
    /// Seconds between flushes to disk: after a crash `metrocell bag recover` keeps everything older than about twice this
    #[arg(long, default_value_t = 1.0)]
    flush_interval: f64,
    /// Reader queue (keep-last depth) of ordinary topics: absorbs stalls of the recorder's taker thread of depth ÷ rate
    #[arg(long, default_value_t = 1000)]
    queue_depth: u32,
    /// Bytes of samples taken from DDS but not yet written that the recorder holds while the disk catches up (as ros2 bag record's --max-cache-size)
    #[arg(long, default_value_t = 256 << 20)]
    max_cache_size: u64,
    /// Name of the recorder node
    #[arg(long, default_value = "recorder")]
    node_name: String,
    /// ROS arguments, after `--`: --ros-args -r __node:=NAME -p name:=value ...
    #[arg(last = true)]
    ros_args: Vec<String>,
}

pub fn run(args: RecordArgs) -> anyhow::Result<i32> {
    if args.topics.is_empty() && !args.all && args.regex.is_none() {
        anyhow::bail!("say what to record: topic names, -a (every topic) or -e REGEX; see --help");
    }
    if args.all && (!args.topics.is_empty() || args.regex.is_some()) {
        anyhow::bail!("-a records every topic: give it without topic names or -e");
    }
    if let Some(t) = args.topics.iter().find(|t| !t.starts_with('/')) {
        anyhow::bail!("topic {t:?}: give the full name, starting with '/'");
    }
    if !(args.max_bag_duration.is_finite() && args.max_bag_duration >= 0.0) {
        anyhow::bail!(
            "--max-bag-duration {}: must be a non-negative number of seconds",
            args.max_bag_duration
        );
    }
    if !(0.1..=60.0).contains(&args.flush_interval) {
        anyhow::bail!(
            "--flush-interval {}: must be between 0.1 and 60 seconds",
            args.flush_interval
        );
    }
    if let Some(o) = &args.output {
        if o.exists() {
            anyhow::bail!("{} exists; give a new bag directory with -o", o.display());
        }
    }
    let mut decls = parameters::declarations();
    if let Some(o) = &args.output {
        set(&mut decls, "output", o.display().to_string());
    }
    set(&mut decls, "topics", args.topics.clone());
    set(&mut decls, "regex", args.regex.clone().unwrap_or_default());
    set(
        &mut decls,
        "exclude",
        args.exclude.clone().unwrap_or_default(),
    );
    set(&mut decls, "compression", args.compression_format.clone());
    set(&mut decls, "flush_interval", args.flush_interval);
    set(
        &mut decls,
        "max_bag_size",
        i64::try_from(args.max_bag_size).unwrap_or(i64::MAX),
    );
    set(&mut decls, "max_bag_duration", args.max_bag_duration);
    set(
        &mut decls,
        "queue_depth",
        i64::from(args.queue_depth.max(1)),
    );
    set(
        &mut decls,
        "max_cache_size",
        i64::try_from(args.max_cache_size.max(1)).unwrap_or(i64::MAX),
    );
    if let Some(p) = &args.qos_profile_overrides_path {
        set(
            &mut decls,
            "qos_profile_overrides_path",
            p.display().to_string(),
        );
    }
    let argv =
        std::iter::once("metrocell bag record".to_string()).chain(args.ros_args.iter().cloned());
    let (builder, _) = MetrocellNode::builder(&args.node_name)
        .params(decls)
        .args(argv)?;
    let mut node = builder.build()?;
    let settings = RecorderSettings::from_node(&node).map_err(|e| anyhow::anyhow!("{e}"))?;
    eprintln!(
        "metrocell bag record: recording into {} (Ctrl-C to finish)",
        settings.output
    );
    match record(&mut node, &settings) {
        Ok(summary) => {
            println!("{}: {}", summary.output, summary.describe());
            Ok(0)
        }
        Err(e) => {
            eprintln!("metrocell bag record: {e}");
            if let Some(s) = e.summary {
                eprintln!("{}", s.describe());
            }
            Ok(1)
        }
    }
}
