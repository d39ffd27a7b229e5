//! [`write_bag`]: a simulation recorded as a rosbag2 MCAP bag, deterministically.
//!
//! Every message is written with log time = publish time = its stamp (simulated time, see
//! [`crate::sim_time`]); topics are registered in [`TopicMap`] order with their full
//! definitions and QoS. Same cell, duration, seed and options → byte-identical `.mcap` and
//! `metadata.yaml` (the writer's wall-clock flush timer is disabled: chunks close by size only,
//! and the bag is regenerable, so losing an unfinished one to a crash costs nothing). The
//! bag's file names derive from the directory name, so compare bags written under the same
//! directory name. metadata.yaml's `ros_distro` is taken from `$ROS_DISTRO` by the writer.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use metrocell_bag::{qos_profiles_yaml, BagMetadata, BagWriter, ChunkCompression, WriterOptions};
use metrocell_twin::{Cell, Simulation};

use crate::camera_frame::FrameRendering;
use crate::camera_intrinsics::CameraIntrinsics;
use crate::error::SimError;
use crate::message_stream::{MessageConverter, MessageStream};
use crate::sim_time::{check_span, parse_start_time, DEFAULT_START_TIME};

/// Default `/clock` rate in a bag (ticks per simulated second).
pub const DEFAULT_BAG_CLOCK_RATE: f64 = 10.0;

/// Options of [`write_bag`].
#[derive(Debug, Clone)]
pub struct BagOptions {
    /// Start of simulated time, ns since the Unix epoch.
    pub start_ns: u64,
    pub compression: ChunkCompression,
    /// `/clock` ticks per simulated second; `None` leaves `/clock` out of the bag.
    pub clock_rate: Option<f64>,
    pub camera: CameraIntrinsics,
    /// How camera frames are rendered; `None` records `CameraInfo` only.
    pub frames: Option<FrameRendering>,
    /// Uncompressed MCAP chunk size (bytes).
    pub chunk_size: u64,
    /// Threads rendering camera frames while the simulation runs ahead (0 = render on the
    /// writing thread). The bag's bytes do not depend on it. Default: one per core.
    pub render_threads: usize,
}

impl Default for BagOptions {
    fn default() -> Self {
        BagOptions {
            start_ns: parse_start_time(DEFAULT_START_TIME).expect("the default start time parses"),
            compression: ChunkCompression::Zstd,
            clock_rate: Some(DEFAULT_BAG_CLOCK_RATE),
            camera: CameraIntrinsics::default(),
            frames: Some(FrameRendering::default()),
            chunk_size: 4 << 20,
            render_threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

/// Where a running [`write_bag`] is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Simulated time reached (s) and the run's duration (s).
    pub t: f64,
    pub duration: f64,
    pub messages: u64,
}

/// What [`write_bag`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct BagSummary {
    pub dir: PathBuf,
    /// Messages per topic name (every topic of the map, zero counts included).
    pub messages_per_topic: BTreeMap<String, u64>,
    pub total_messages: u64,
    /// The final metadata.yaml content.
    pub metadata: BagMetadata,
}

/// Messages between two progress callbacks.
const PROGRESS_EVERY: u64 = 1 << 14;

/// Simulate `cell` for `duration_s` seconds with `seed` and record every message into the
/// bag directory `out_dir` (created; must not already hold a bag). `progress` is called every
/// few thousand messages and once at the end.
pub fn write_bag(
    cell: Cell,
    duration_s: f64,
    seed: u64,
    out_dir: &Path,
    options: &BagOptions,
    mut progress: impl FnMut(Progress),
) -> Result<BagSummary, SimError> {
    check_span(options.start_ns, duration_s)?;
    if let Some(r) = options.clock_rate {
        if !(r > 0.0 && r.is_finite()) {
            return Err(SimError::invalid(
                "clock rate",
                format!("must be > 0 Hz and finite, got {r}"),
            ));
        }
    }
    let mut converter = MessageConverter::new(&cell, options.start_ns, options.camera.clone())?;
    if let Some(rendering) = &options.frames {
        converter = converter.with_frames(rendering.clone(), seed)?;
    }
    let sim = Simulation::new(cell, duration_s, seed)?;
    let bag_err = |source| SimError::Bag {
        dir: out_dir.to_path_buf(),
        source,
    };
    let writer_options = WriterOptions {
        compression: options.compression,
        chunk_size: options.chunk_size,
        // No wall-clock flushes: chunk boundaries (and so the bytes) depend on the data only.
        flush_interval: Duration::from_secs(10 * 365 * 86_400),
        sync_on_flush: true,
        compression_threads: 0,
        ..WriterOptions::default()
    };
    let mut writer = BagWriter::create(out_dir, writer_options).map_err(bag_err)?;
    let topics = &converter.topics.topics;
    for t in topics {
        writer
            .add_topic(
                &t.name,
                t.ros_type,
                t.definition,
                &qos_profiles_yaml(&[t.qos.bag_profile()]),
            )
            .map_err(bag_err)?;
    }
    let mut counts = vec![0u64; topics.len()];
    let mut total = 0u64;
    let mut stream = MessageStream::new(&sim, &converter, options.clock_rate.map(|r| 1.0 / r))
        .with_render_threads(options.render_threads);
    for m in stream.by_ref() {
        let bytes = m.message.encode()?;
        writer
            .write(&topics[m.topic].name, m.stamp_ns, m.stamp_ns, &bytes)
            .map_err(bag_err)?;
        counts[m.topic] += 1;
        total += 1;
        if total.is_multiple_of(PROGRESS_EVERY) {
            progress(Progress {
                t: m.t,
                duration: duration_s,
                messages: total,
            });
        }
    }
    if let Some(e) = stream.error() {
        return Err(e);
    }
    let metadata = writer.finish().map_err(bag_err)?;
    progress(Progress {
        t: duration_s,
        duration: duration_s,
        messages: total,
    });
    Ok(BagSummary {
        dir: out_dir.to_path_buf(),
        messages_per_topic: topics
            .iter()
            .zip(&counts)
            .map(|(t, &n)| (t.name.clone(), n))
            .collect(),
        total_messages: total,
        metadata,
    })
}
