//! The recorder's parameters and the writer options built from them.

use std::collections::BTreeMap;
use std::time::Duration;

use metrocell_bag::{ChunkCompression, SplitPolicy, WriterOptions};
use metrocell_bagtools::qos_overrides::{read_qos_overrides, QosOverride};
use metrocell_bagtools::TopicSelection;
use metrocell_node::{MetrocellNode, ParamDecl};

/// Everything the recorder needs, checked.
#[derive(Debug, Clone)]
pub struct RecorderSettings {
    pub output: String,
    pub selection: TopicSelection,
    pub writer_options: WriterOptions,
    pub queue_depth: usize,
    pub bulk_queue_depth: usize,
    pub qos_overrides: BTreeMap<String, QosOverride>,
    pub scan_interval: Duration,
    /// Bytes of samples taken from the readers and not yet written that the recorder holds
    /// before it stops taking (rosbag2's `--max-cache-size`).
    pub max_cache_bytes: usize,
    /// Go on in `output` when it already holds a bag (a recorder that did not finish).
    pub resume: bool,
}

impl RecorderSettings {
    pub fn from_node(node: &MetrocellNode) -> Result<Self, Box<dyn std::error::Error>> {
        let output = match node.param::<String>("output")? {
            o if o.is_empty() => default_output(),
            o => o,
        };
        let path = node.param::<String>("qos_profile_overrides_path")?;
        let qos_overrides = if path.is_empty() {
            BTreeMap::new()
        } else {
            read_qos_overrides(std::path::Path::new(&path))?
        };
        let depth = |name: &str| -> Result<usize, Box<dyn std::error::Error>> {
            Ok(node.param::<i64>(name)?.clamp(1, 1_000_000) as usize)
        };
        Ok(Self {
            output,
            selection: selection(node)?,
            writer_options: writer_options(node)?,
            queue_depth: depth("queue_depth")?,
            bulk_queue_depth: depth("bulk_queue_depth")?,
            qos_overrides,
            scan_interval: Duration::from_secs_f64(node.param::<f64>("scan_interval")?),
            max_cache_bytes: node.param::<i64>("max_cache_size")?.max(1) as usize,
            resume: node.param::<bool>("resume")?,
        })
    }
}

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("output", String::new(), "bag directory to create (default bag_<UTC timestamp>)"),
        ParamDecl::new("resume", false, "when output already holds a bag (a recorder killed before it finished, e.g. respawned by launch): recover it and go on recording into a new split file of it, instead of refusing"),
        ParamDecl::new("topics", Vec::<String>::new(), "topics to record (empty: every discovered topic)"),
        ParamDecl::new("regex", String::new(), "record only topics matching this regex (whole name)"),
        ParamDecl::new("exclude", String::new(), "do not record topics matching this regex (whole name)"),
        ParamDecl::new("compression", "zstd".to_string(), "chunk compression: zstd, lz4 or none"),
        ParamDecl::new("flush_interval", 1.0, "seconds between flushes to disk: a kill loses at most ~2x this").with_range(0.1, 60.0),
        ParamDecl::new("max_bag_size", 0i64, "split into a new .mcap file after this many bytes (0: never)"),
        ParamDecl::new("max_bag_duration", 0.0, "split into a new .mcap file after this many seconds (0: never)").with_range(0.0, 1e9),
        ParamDecl::new("queue_depth", 1000i64, "DDS reader history (keep-last depth) of ordinary topics: covers stalls of the taker thread of depth / rate seconds").with_range(1.0, 1e6),
        ParamDecl::new("max_cache_size", 256i64 << 20, "bytes of samples taken from the DDS readers but not yet written that the recorder holds (a slow disk); when full it stops taking and samples wait in the readers' queues").with_range(1.0, 1e12),
        ParamDecl::new("fail_after_bytes", 0i64, "testing only: simulate a full disk after this many bytes per file (0: off)"),
        ParamDecl::new("qos_profile_overrides_path", String::new(), "YAML file of per-topic reader QoS (rosbag2's format: /topic: {reliability: reliable, durability: transient_local, history: keep_last, depth: 100})"),
        ParamDecl::new("scan_interval", 1.0, "seconds between looks at discovery for new topics").with_range(0.05, 60.0),
        ParamDecl::new("bulk_queue_depth", 30i64, "history of bulk topics (types with a byte-array field, e.g. images); RustDDS keeps this many samples in memory, so memory ≈ depth × message size").with_range(1.0, 1e6),
    ]
}

pub fn selection(node: &MetrocellNode) -> Result<TopicSelection, Box<dyn std::error::Error>> {
    let topics = node
        .param::<Vec<String>>("topics")?
        .iter()
        .map(|t| node.resolve_topic(t))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(TopicSelection::new(
        topics,
        &node.param::<String>("regex")?,
        &node.param::<String>("exclude")?,
    )?)
}

pub fn writer_options(node: &MetrocellNode) -> Result<WriterOptions, Box<dyn std::error::Error>> {
    let compression = match node.param::<String>("compression")?.as_str() {
        "zstd" => ChunkCompression::Zstd,
        "lz4" => ChunkCompression::Lz4,
        "none" | "" => ChunkCompression::None,
        other => {
            return Err(
                format!("parameter compression: '{other}' is not one of zstd, lz4, none").into(),
            )
        }
    };
    let size = node.param::<i64>("max_bag_size")?;
    let duration = node.param::<f64>("max_bag_duration")?;
    Ok(WriterOptions {
        compression,
        flush_interval: Duration::from_secs_f64(node.param::<f64>("flush_interval")?),
        split: SplitPolicy {
            max_file_bytes: (size > 0).then_some(size as u64),
            max_file_duration: (duration > 0.0).then(|| Duration::from_secs_f64(duration)),
        },
        fail_after_bytes: match node.param::<i64>("fail_after_bytes")? {
            n if n > 0 => Some(n as u64),
            _ => None,
        },
        ..WriterOptions::default()
    })
}

/// `bag_YYYY_MM_DD-HH_MM_SS` in UTC, like rosbag2's default names.
pub fn default_output() -> String {
    let now_ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0);
    // "YYYY-MM-DD hh:mm:ss.nnnnnnnnn" → "bag_YYYY_MM_DD-hh_mm_ss"
    let stamp = metrocell_bag::format_utc(now_ns);
    format!(
        "bag_{}",
        stamp[..19]
            .replace('-', "_")
            .replace(' ', "-")
            .replace(':', "_")
    )
}
