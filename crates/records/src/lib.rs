//! # metrocell-records — measurement records from recordings
//!
//! Decodes what the nodes record (ROS 2 messages, from a bag or live from DDS) into the
//! [`metrocell_estimation::RecordSet`] the estimation numerics consume. The record types
//! themselves and everything done with them (residuals, fits, the online filter) live in
//! crates/estimation, which links neither the bag stack nor the messages; this crate is the
//! one place where a message becomes a record. Used by `metrocell calibrate`, `metrocell
//! diagnose`, `metrocell compensate`, the estimator node and the diagnose node.
//!
//! * [`recordings`] — [`records_from_bags`]: bags (the nodes', `metrocell sim`'s, `bag import`'s)
//!   → a [`RecordSet`](metrocell_estimation::RecordSet) for the shared model, signals by the
//!   model's `SignalsBuilder`; missing signals named with the topics and columns that would
//!   provide them.
//! * [`record_stream`] — the same, one message at a time ([`RecordStream`]): what a bag
//!   replay and a live node (the estimator and diagnose nodes) feed, records out in time order;
//!   `recording_sources` checks first which topics give its records and signals.
//! * [`instrument_readings`] — probe hits and camera marker poses in a recording → what their
//!   records measure and what the model needs to predict them.
//! * [`signal_topics`] — the recorded topics that carry signals and how each message feeds the
//!   signals builder (shared with the online estimator).
//!
//! Units: SI (m, s, °C as `sensor_msgs/Temperature` carries them) in and out.

pub mod instrument_readings;
pub mod record_stream;
mod recording_sources;
pub mod recordings;
pub mod signal_topics;

pub use record_stream::{declared_topics, RecordStream, StreamOutput, LAG_FULL_RATE_MARGIN_S};
pub use recordings::{records_from_bags, PointSource, RecordingError, RecordingOptions};
