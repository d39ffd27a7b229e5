//! Library code of the `metrocell bag` command and the `metrocell-recorder` node. No DDS here:
//! the node and the CLI own the DDS endpoints and call these functions with bytes and times.
//!
//! * [`TopicSelection`]: which topics a recorder records (list, regex, exclude).
//! * [`Recording`]: a [`metrocell_bag::BagWriter`] plus per-topic counts and dropped-message
//!   detection from per-publisher sequence numbers.
//! * [`compare_counts`]: a bag's per-topic counts against what a publisher says it sent.
//! * [`filter_bag`] / [`merge_bags`]: copy selected messages into a new bag.
//! * [`export`]: one CSV file per topic, one column per leaf field.
//! * Parquet export (the same columns, typed) lives in `metrocell-parquet-export`, so that the
//!   nodes, which link this crate for offline replay, do not link Parquet.
//! * [`export_manifest`]: `export.yaml`, each exported file's topic, type, definition and QoS.
//! * [`import`]: point-measurement CSV (own layout or a mapped tracker export) → bag.
//! * [`reimport`]: `bag export`'s files back into a bag, every message as it was recorded.
//! * [`recorded_qos`]: offered QoS of discovered publishers → `offered_qos_profiles` and the
//!   QoS the recorder requests; stored profiles → the QoS `bag play` offers.
//! * [`qos_overrides`]: the `--qos-profile-overrides-path` file of `ros2 bag record/play`.
//! * [`playback`]: the timing of `bag play` (rate, pause, step) as a pure schedule.
//! * [`is_bulk_type`]: message types of megabytes (images), which readers queue briefly.
//! * [`BagSource`]: offline replay — a node reads typed messages from a bag instead of DDS.
//! * [`BagSink`]: offline replay — the node writes its outputs to a bag at bag time.
//! * [`ReplayOutput`]: a replaying node's outputs, to a bag or as JSON lines on stdout.

mod bag_sink;
mod bag_source;
mod bulk_types;
mod completeness;
mod copy;
mod error;
pub mod export;
pub mod export_manifest;
pub mod import;
pub mod playback;
pub mod qos_overrides;
pub mod recorded_qos;
mod recording;
pub mod reimport;
mod replay_output;
mod topic_selection;

pub use bag_sink::{encode_cdr, BagSink};
pub use bag_source::{BagSource, SourcedMessage};
pub use bulk_types::is_bulk_type;
pub use completeness::{compare_counts, CountMismatch};
pub use copy::{filter_bag, merge_bags, CopyReport};
pub use error::{io, Result, ToolError};
pub use recording::{Recording, SequenceGap, TopicCounts, TopicDefinition, NAMED_GAPS};
pub use replay_output::ReplayOutput;
pub use topic_selection::TopicSelection;
