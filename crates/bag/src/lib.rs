//! MCAP recording and replay in the rosbag2 layout, crash-safe and readable by ROS 2 tools.
//!
//! * [`BagWriter`] records CDR messages into `<dir>/<dirname>_N.mcap` + `metadata.yaml`
//!   (profile `ros2`, schema encoding `ros2msg`, message encoding `cdr`), flushing a closed
//!   chunk to disk every `flush_interval` so a killed recorder loses at most that much.
//! * [`BagReader`] reads a bag directory or one `.mcap` file in log-time order, strictly or
//!   tolerantly ([`ReadMode`]), with errors naming file, byte offset and record kind.
//! * [`recover`] rebuilds a valid bag from files cut at any byte or left without summary.
//! * [`info`] summarises a bag like `ros2 bag info`.
//!
//! No DDS here: the recorder node hands raw CDR bytes (with encapsulation header) to the writer.

mod durable_file;
mod error;
mod info;
mod mcap_tail;
mod metadata;
pub mod msgdef;
mod options;
mod qos;
mod reader;
mod record_layout;
mod recover;
mod scan;
mod writer;

pub use error::{BagError, Result};
pub use info::{format_utc, info, BagInfo, FileSummary, TopicSummary};
pub use metadata::{
    BagMetadata, FileInformation, Nanoseconds, NanosecondsSinceEpoch, TopicMetadata,
    TopicWithMessageCount, METADATA_FILE,
};
pub use options::{ChunkCompression, SplitPolicy, WriterOptions, MIN_FLUSH_INTERVAL};
pub use qos::{
    offered_qos_yaml, parse_offered_qos, qos_profiles_yaml, validate_qos_yaml, OfferedQos,
    QosProfile, RmwDuration, DURABILITY_TRANSIENT_LOCAL, DURABILITY_VOLATILE, HISTORY_KEEP_ALL,
    HISTORY_KEEP_LAST, HISTORY_UNKNOWN, LIVELINESS_AUTOMATIC, LIVELINESS_MANUAL_BY_TOPIC,
    RELIABILITY_BEST_EFFORT, RELIABILITY_RELIABLE,
};
pub use reader::{BagMessage, BagReader, MessageFilter, MessageIter, ReadMode, TopicInfo};
pub use recover::{recover, recover_with, FileRecovery, RecoverOptions, RecoveryReport};
pub use scan::record_kind;
pub use writer::{BagWriter, LIBRARY};
