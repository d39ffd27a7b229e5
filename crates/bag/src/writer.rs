//! [`BagWriter`]: records CDR messages into a rosbag2 directory of MCAP files.
//!
//! Layout: `<dir>/<dirname>_0.mcap`, `_1.mcap`, ... and `<dir>/metadata.yaml`. Each MCAP file
//! uses profile `ros2`, schema encoding `ros2msg` (schema name `pkg/msg/Type`, data = the
//! full .msg text with dependencies), message encoding `cdr`, and channel metadata
//! `offered_qos_profiles` + `topic_type_hash`, as rosbag2's MCAP storage plugin writes them.
//!
//! # Crash-safety bound
//! Messages go into an in-memory chunk. A *flush* closes that chunk, writes it (with its
//! message indexes) to the file, flushes the OS buffer, fdatasyncs when
//! [`WriterOptions::sync_on_flush`] is set, and rewrites metadata.yaml. A flush runs
//! (a) inside `write`/`tick` whenever at least `flush_interval` of wall-clock time has passed
//! since the previous flush, (b) when a file is split or finished, and (c) on `flush()`. A
//! chunk that reaches `chunk_size` is closed into the 1 MiB file buffer but not flushed, so
//! it may or may not survive a crash; only flushes are promised.
//! So if the process is killed at wall-clock time `t_kill`, every message whose `write`
//! returned before the last flush is recoverable, and the messages lost are exactly those
//! written after it: with `write`/`tick` called at least every `P` seconds, that is at most
//! the messages of the last `flush_interval + P` seconds (the recorder node calls `tick`
//! from a timer with `P <= flush_interval`, so the bound is `2 * flush_interval`; for a
//! stream that writes continuously it is `flush_interval` plus one inter-message gap).
//! With `sync_on_flush` the same bound holds for power loss.
//!
//! # Write failures
//! On the first failed write (disk full, I/O error) the writer stops: it cuts the file back
//! to the end of the last completed flush (a record boundary), appends `DataEnd`, `Footer`
//! and the end magic (a valid MCAP without a summary section), rewrites metadata.yaml with
//! the counts as of that flush, and returns [`BagError::WriteFailed`] naming the file.
//! Later calls return [`BagError::Closed`].

use std::collections::{BTreeMap, HashMap};
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::durable_file::{lock_state, DurableFile, SinkState};
use crate::error::{io_err, BagError, Result};
use crate::metadata::{
    BagMetadata, FileInformation, Nanoseconds, NanosecondsSinceEpoch, TopicMetadata,
    TopicWithMessageCount, METADATA_FILE,
};
use crate::options::{ChunkCompression, WriterOptions, MIN_FLUSH_INTERVAL};
use crate::qos::validate_qos_yaml;

/// MCAP header `library` string of files written here.
pub const LIBRARY: &str = concat!(
    "metrocell-bag/",
    env!("CARGO_PKG_VERSION"),
    "; mcap-rust/0.26"
);

/// Message / time statistics of one file, or of the part of it that is on disk.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Span {
    count: u64,
    start: u64,
    end: u64,
}

impl Span {
    fn add(&mut self, t: u64) {
        if self.count == 0 {
            self.start = t;
            self.end = t;
        } else {
            self.start = self.start.min(t);
            self.end = self.end.max(t);
        }
        self.count += 1;
    }
    fn merge(&mut self, o: &Span) {
        if o.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = *o;
        } else {
            self.start = self.start.min(o.start);
            self.end = self.end.max(o.end);
            self.count += o.count;
        }
    }
}

struct TopicEntry {
    meta: TopicMetadata,
    /// MCAP schema encoding: `ros2msg`, or "" for a type recorded without its definition.
    schema_encoding: &'static str,
    definition: String,
    sequence: u32,
    /// Messages handed to `write` (all files).
    written: u64,
    /// Messages on disk as of the last flush (all files).
    durable: u64,
}

struct OpenFile {
    name: String,
    path: PathBuf,
    mcap: mcap::Writer<DurableFile>,
    sink: Arc<Mutex<SinkState>>,
    /// MCAP channel id per topic index.
    channel_ids: Vec<u16>,
    written: Span,
    durable: Span,
    /// File length at the end of the last completed flush (a record boundary).
    sealed_len: u64,
}

/// Records messages into a rosbag2 MCAP bag directory. See the module doc for the
/// crash-safety bound and failure behaviour.
pub struct BagWriter {
    dir: PathBuf,
    base_name: String,
    options: WriterOptions,
    topics: Vec<TopicEntry>,
    topic_index: HashMap<String, usize>,
    finished_files: Vec<FileInformation>,
    current: Option<OpenFile>,
    closed: Option<String>,
    last_flush: Instant,
}

impl BagWriter {
    /// Create the bag directory `dir` (it may exist but must not hold a bag yet) and its first
    /// file `<dir>/<dirname>_0.mcap`, and write an initial metadata.yaml.
    pub fn create(dir: impl AsRef<Path>, options: WriterOptions) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        check_options(&options)?;
        std::fs::create_dir_all(&dir).map_err(io_err("create directory", &dir))?;
        if dir.join(METADATA_FILE).exists() {
            return Err(BagError::InvalidArgument(format!(
                "{} already holds a bag (metadata.yaml exists)",
                dir.display()
            )));
        }
        Self::start(dir, options, Vec::new())
    }

    /// Go on recording into the bag at `dir` after its writer stopped without finishing (a
    /// recorder killed and respawned): the bag is first recovered in place ([`crate::recover`]:
    /// every message that reached the disk intact is kept; a rewritten file's original stays as
    /// `<file>.orig`), then a new split file `<dirname>_<n>.mcap` is opened after the existing
    /// ones, with the bag's topics declared again and their counts carried on. A directory
    /// without a bag is created as by [`BagWriter::create`]. Also returns the recovery's report
    /// (None when there was no bag to go on from).
    pub fn append(
        dir: impl AsRef<Path>,
        options: WriterOptions,
    ) -> Result<(Self, Option<crate::recover::RecoveryReport>)> {
        let dir = dir.as_ref().to_path_buf();
        if !dir.join(METADATA_FILE).exists() {
            return Ok((Self::create(dir, options)?, None));
        }
        check_options(&options)?;
        let report = crate::recover::recover(&dir)?;
        let metadata = BagMetadata::read_dir(&dir)?;
        let topics = crate::reader::BagReader::open(&dir)?.topics().to_vec();
        let mut w = Self::start(dir, options, metadata.files.clone())?;
        for t in &topics {
            let count = metadata
                .topics_with_message_count
                .iter()
                .find(|m| m.topic_metadata.name == t.name)
                .map_or(t.message_count, |m| m.message_count);
            let definition = (t.schema_encoding == "ros2msg" && !t.definition.is_empty())
                .then_some(t.definition.as_str());
            w.declare_topic(
                &t.name,
                &t.type_name,
                definition,
                &t.offered_qos_profiles,
                &t.type_description_hash,
            )?;
            let i = w.topic_index[&t.name];
            w.topics[i].written = count;
            w.topics[i].durable = count;
        }
        w.write_metadata(false)?;
        Ok((w, Some(report)))
    }

    /// A writer on `dir` after the `finished` files, its next split file open.
    fn start(dir: PathBuf, options: WriterOptions, finished: Vec<FileInformation>) -> Result<Self> {
        let base_name = dir
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| !n.is_empty())
            .ok_or_else(|| {
                BagError::InvalidArgument(format!(
                    "bag directory {} has no usable name",
                    dir.display()
                ))
            })?
            .to_string();
        let mut w = Self {
            dir,
            base_name,
            options,
            topics: Vec::new(),
            topic_index: HashMap::new(),
            finished_files: finished,
            current: None,
            closed: None,
            last_flush: Instant::now(),
        };
        if let Err(e) = w.open_next_file().and_then(|_| w.write_metadata(false)) {
            return Err(w.fail(e));
        }
        Ok(w)
    }

    /// The bag directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Path of the file currently being written.
    pub fn current_file(&self) -> Option<&Path> {
        self.current.as_ref().map(|f| f.path.as_path())
    }

    /// Declare a topic: `ros_type` is `pkg/msg/Type`, `definition` the full ros2msg text
    /// (the type's .msg followed by each dependency after a line of 80 `=` and `MSG: pkg/Type`),
    /// `qos_yaml` the `offered_qos_profiles` YAML (see [`crate::qos_profiles_yaml`]).
    /// Declaring the same topic again with the same type is a no-op.
    pub fn add_topic(
        &mut self,
        name: &str,
        ros_type: &str,
        definition: &str,
        qos_yaml: &str,
    ) -> Result<()> {
        self.add_topic_with_hash(name, ros_type, definition, qos_yaml, "")
    }

    /// Declare a topic whose type's definition is not known (raw CDR is still recorded).
    /// Its MCAP schema has the type's name, an empty encoding and no data — what the MCAP
    /// specification prescribes for "no definition" and what `rosbags` reads as a message
    /// definition of format NONE. (rosbag2 writes encoding `unknown` in this case, which
    /// rosbags rejects.)
    pub fn add_topic_without_definition(
        &mut self,
        name: &str,
        ros_type: &str,
        qos_yaml: &str,
    ) -> Result<()> {
        self.declare_topic(name, ros_type, None, qos_yaml, "")
    }

    /// [`Self::add_topic`] with a type description hash (`RIHS01_...`, may be empty).
    pub fn add_topic_with_hash(
        &mut self,
        name: &str,
        ros_type: &str,
        definition: &str,
        qos_yaml: &str,
        type_hash: &str,
    ) -> Result<()> {
        self.declare_topic(name, ros_type, Some(definition), qos_yaml, type_hash)
    }

    /// `definition`: the full ros2msg text, or `None` when the type's definition is unknown.
    fn declare_topic(
        &mut self,
        name: &str,
        ros_type: &str,
        definition: Option<&str>,
        qos_yaml: &str,
        type_hash: &str,
    ) -> Result<()> {
        self.check_open()?;
        if !name.starts_with('/') {
            return Err(BagError::InvalidArgument(format!(
                "topic name {name:?} must start with '/'"
            )));
        }
        let parts: Vec<&str> = ros_type.split('/').collect();
        if parts.len() != 3 || parts.iter().any(|p| p.is_empty()) {
            return Err(BagError::InvalidArgument(format!(
                "type {ros_type:?} of topic {name} is not of the form pkg/msg/Type"
            )));
        }
        if let Some(definition) = definition {
            crate::msgdef::parse_definition(ros_type, definition)?;
        }
        validate_qos_yaml(name, qos_yaml)?;
        if let Some(&i) = self.topic_index.get(name) {
            if self.topics[i].meta.type_name == ros_type {
                return Ok(());
            }
            return Err(BagError::InvalidArgument(format!(
                "topic {name} already declared with type {}, not {ros_type}",
                self.topics[i].meta.type_name
            )));
        }
        self.topics.push(TopicEntry {
            meta: TopicMetadata {
                name: name.to_string(),
                type_name: ros_type.to_string(),
                serialization_format: "cdr".into(),
                offered_qos_profiles: qos_yaml.to_string(),
                type_description_hash: type_hash.to_string(),
            },
            schema_encoding: if definition.is_some() { "ros2msg" } else { "" },
            definition: definition.unwrap_or_default().to_string(),
            sequence: 0,
            written: 0,
            durable: 0,
        });
        let idx = self.topics.len() - 1;
        self.topic_index.insert(name.to_string(), idx);
        // Flush so the schema/channel are on disk, and list the topic in metadata.yaml now.
        let res = self
            .register_topic_in_current(idx)
            .and_then(|_| self.flush_now(false))
            .and_then(|_| self.write_metadata(false));
        if let Err(e) = res {
            return Err(self.fail(e));
        }
        Ok(())
    }

    /// Record one message. `cdr` must start with the 4-byte CDR encapsulation header
    /// (`00 01 00 00` for little-endian). Times are nanoseconds since the Unix epoch; the log
    /// time is the receive time and orders replay.
    pub fn write(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        publish_time_ns: u64,
        cdr: &[u8],
    ) -> Result<()> {
        self.check_open()?;
        let idx = *self.topic_index.get(topic).ok_or_else(|| {
            BagError::InvalidArgument(format!("topic {topic} was not added with add_topic"))
        })?;
        if cdr.len() < 4 || cdr[0] != 0 || cdr[1] > 0x0b {
            return Err(BagError::InvalidArgument(format!(
                "message on {topic} does not start with a CDR encapsulation header (got {:02x?})",
                &cdr[..cdr.len().min(4)]
            )));
        }
        if let Err(e) = self.split_if_due(log_time_ns) {
            return Err(self.fail(e));
        }
        let t = &mut self.topics[idx];
        t.sequence = t.sequence.wrapping_add(1);
        let f = self.current.as_mut().expect("open after check_open");
        let header = mcap::records::MessageHeader {
            channel_id: f.channel_ids[idx],
            sequence: t.sequence,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        if let Err(e) = f.mcap.write_to_known_channel(&header, cdr) {
            let e = mcap_to_bag(&f.path, &f.sink, e);
            return Err(self.fail(e));
        }
        f.written.add(log_time_ns);
        t.written += 1;
        self.tick()
    }

    /// Flush if `flush_interval` has elapsed since the last flush. Call this from a timer
    /// (period <= flush_interval) when messages may stop arriving; see the module doc.
    pub fn tick(&mut self) -> Result<()> {
        self.check_open()?;
        if self.last_flush.elapsed() >= self.options.flush_interval {
            if let Err(e) = self.flush_now(true) {
                return Err(self.fail(e));
            }
        }
        Ok(())
    }

    /// Flush now: close the chunk, write and fsync it, rewrite metadata.yaml.
    pub fn flush(&mut self) -> Result<()> {
        self.check_open()?;
        if let Err(e) = self.flush_now(true) {
            return Err(self.fail(e));
        }
        Ok(())
    }

    /// Messages written so far (including any not yet flushed).
    pub fn message_count(&self) -> u64 {
        self.topics.iter().map(|t| t.written).sum()
    }

    /// Messages on disk as of the last flush.
    pub fn durable_message_count(&self) -> u64 {
        self.topics.iter().map(|t| t.durable).sum()
    }

    /// Write the summary section of the last file and the final metadata.yaml.
    pub fn finish(mut self) -> Result<BagMetadata> {
        self.finish_inner()
    }

    fn finish_inner(&mut self) -> Result<BagMetadata> {
        self.check_open()?;
        if let Err(e) = self.finish_current_file() {
            return Err(self.fail(e));
        }
        self.write_metadata(true)?;
        self.closed = Some("finished".into());
        Ok(self.metadata_snapshot())
    }

    // ----- internals -------------------------------------------------------------------

    fn check_open(&self) -> Result<()> {
        match &self.closed {
            Some(reason) => Err(BagError::Closed {
                path: self.dir.clone(),
                reason: reason.clone(),
            }),
            None => Ok(()),
        }
    }

    fn mcap_options(&self) -> mcap::WriteOptions {
        let mut o = mcap::WriteOptions::new()
            .profile("ros2")
            .library(LIBRARY)
            .compression(self.options.compression.to_mcap())
            .chunk_size(Some(self.options.chunk_size))
            .use_chunks(true)
            .disable_seeking(true);
        // The level is zstd's; lz4 keeps its fast mode (levels >= 3 switch it to LZ4HC).
        if self.options.compression == ChunkCompression::Zstd {
            o = o.compression_level(self.options.compression_level);
        }
        o.compression_threads(self.options.compression_threads)
    }

    fn open_next_file(&mut self) -> Result<()> {
        let name = format!("{}_{}.mcap", self.base_name, self.finished_files.len());
        let path = self.dir.join(&name);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(io_err("create", &path))?;
        let sink = DurableFile::new(
            file,
            self.options.sync_on_flush,
            self.options.fail_after_bytes,
        );
        let state = sink.state.clone();
        let mcap = match self.mcap_options().create(sink) {
            Ok(m) => m,
            Err(e) => {
                // Not even the magic and header made it: leave no non-MCAP file behind.
                let _ = std::fs::remove_file(&path);
                return Err(mcap_to_bag(&path, &state, e));
            }
        };
        self.current = Some(OpenFile {
            name,
            path,
            mcap,
            sink: state,
            channel_ids: Vec::new(),
            written: Span::default(),
            durable: Span::default(),
            sealed_len: 0,
        });
        for i in 0..self.topics.len() {
            self.register_topic_in_current(i)?;
        }
        self.flush_now(false)
    }

    fn register_topic_in_current(&mut self, idx: usize) -> Result<()> {
        let f = self.current.as_mut().expect("a file is open");
        let t = &self.topics[idx];
        let schema_id = f
            .mcap
            .add_schema(
                &t.meta.type_name,
                t.schema_encoding,
                t.definition.as_bytes(),
            )
            .map_err(|e| mcap_to_bag(&f.path, &f.sink, e))?;
        let mut md = BTreeMap::new();
        md.insert(
            "offered_qos_profiles".to_string(),
            t.meta.offered_qos_profiles.clone(),
        );
        md.insert(
            "topic_type_hash".to_string(),
            t.meta.type_description_hash.clone(),
        );
        let ch = f
            .mcap
            .add_channel(schema_id, &t.meta.name, "cdr", &md)
            .map_err(|e| mcap_to_bag(&f.path, &f.sink, e))?;
        debug_assert_eq!(f.channel_ids.len(), idx);
        f.channel_ids.push(ch);
        Ok(())
    }

    /// Close the chunk, flush (+fsync) the file, remember the sealed length and the durable
    /// counts, and (if `metadata`) rewrite metadata.yaml.
    fn flush_now(&mut self, metadata: bool) -> Result<()> {
        let f = self.current.as_mut().expect("a file is open");
        f.mcap
            .flush()
            .map_err(|e| mcap_to_bag(&f.path, &f.sink, e))?;
        f.sealed_len = lock_state(&f.sink).position;
        let changed = f.durable != f.written;
        f.durable = f.written;
        for t in &mut self.topics {
            t.durable = t.written;
        }
        self.last_flush = Instant::now();
        if metadata && changed {
            self.write_metadata(false)?;
        }
        Ok(())
    }

    fn split_if_due(&mut self, log_time: u64) -> Result<()> {
        let f = self.current.as_ref().expect("a file is open");
        if f.written.count == 0 {
            return Ok(());
        }
        let by_size = self
            .options
            .split
            .max_file_bytes
            .is_some_and(|max| lock_state(&f.sink).position >= max);
        let by_time = self.options.split.max_file_duration.is_some_and(|d| {
            log_time.saturating_sub(f.written.start) >= d.as_nanos().min(u64::MAX as u128) as u64
        });
        if by_size || by_time {
            self.finish_current_file()?;
            self.open_next_file()?;
            self.write_metadata(false)?;
        }
        Ok(())
    }

    fn finish_current_file(&mut self) -> Result<()> {
        let mut f = self.current.take().expect("a file is open");
        let doc = self.metadata_with(Some(&f), true).to_inner_yaml();
        let res = (|| {
            let mut md = BTreeMap::new();
            md.insert("serialized_metadata".to_string(), doc);
            f.mcap
                .write_metadata(&mcap::records::Metadata {
                    name: "rosbag2".into(),
                    metadata: md,
                })
                .map_err(|e| mcap_to_bag(&f.path, &f.sink, e))?;
            f.mcap
                .finish()
                .map_err(|e| mcap_to_bag(&f.path, &f.sink, e))?;
            Ok(())
        })();
        if let Err(e) = res {
            self.current = Some(f);
            return Err(e);
        }
        // finish() wrote summary + footer and flushed (and fsynced) the sink.
        drop(f.mcap);
        for t in &mut self.topics {
            t.durable = t.written;
        }
        self.finished_files.push(FileInformation {
            path: f.name.clone(),
            starting_time: NanosecondsSinceEpoch {
                nanoseconds_since_epoch: f.written.start,
            },
            duration: Nanoseconds {
                nanoseconds: f.written.end - f.written.start,
            },
            message_count: f.written.count,
        });
        Ok(())
    }

    /// Stop after a failure: cut the current file back to its last flush and seal it, reset
    /// counts to what is on disk, rewrite metadata.yaml. Returns the error to give the caller.
    fn fail(&mut self, e: BagError) -> BagError {
        let Some(f) = self.current.take() else {
            self.closed = Some(e.to_string());
            return e;
        };
        let OpenFile {
            path,
            mcap,
            sink,
            written,
            durable,
            sealed_len,
            name,
            ..
        } = f;
        {
            let mut st = lock_state(&sink);
            if st.failure.is_none() {
                st.failure = Some(std::io::Error::other("writer stopped after an error"));
            }
        }
        drop(mcap); // its Drop tries finish(); the poisoned sink rejects every byte.
        let lost = written.count - durable.count;
        let seal_result = if sealed_len == 0 {
            // Nothing of this file ever reached the disk intact (not even its header): remove
            // it rather than leave a file that is not MCAP.
            std::fs::remove_file(&path).map_err(io_err("remove", &path))
        } else {
            seal_at(&path, sealed_len, self.options.sync_on_flush)
        };
        for t in &mut self.topics {
            t.written = t.durable;
        }
        if sealed_len > 0 {
            self.finished_files.push(FileInformation {
                path: name,
                starting_time: NanosecondsSinceEpoch {
                    nanoseconds_since_epoch: durable.start,
                },
                duration: Nanoseconds {
                    nanoseconds: durable.end - durable.start,
                },
                message_count: durable.count,
            });
        }
        let meta_result = self.write_metadata(true);
        let source = match e {
            BagError::Io { source, .. } => source,
            BagError::WriteFailed { source, .. } => source,
            other => std::io::Error::other(other.to_string()),
        };
        let err = BagError::WriteFailed {
            path: path.clone(),
            source,
            kept_messages: self.durable_message_count(),
            lost_messages: lost,
        };
        let mut reason = err.to_string();
        if let Err(se) = seal_result {
            reason.push_str(&format!(
                "; sealing failed too ({se}); run recover on the bag"
            ));
        }
        if let Err(me) = meta_result {
            reason.push_str(&format!("; metadata.yaml not rewritten ({me})"));
        }
        self.closed = Some(reason);
        err
    }

    fn metadata_snapshot(&self) -> BagMetadata {
        self.metadata_with(self.current.as_ref(), false)
    }

    /// Metadata for the finished files plus the current file (its durable part, or all of it
    /// when `all_written`).
    fn metadata_with(&self, current: Option<&OpenFile>, all_written: bool) -> BagMetadata {
        let mut m = BagMetadata::empty();
        let mut files = self.finished_files.clone();
        if let Some(f) = current {
            let s = if all_written { f.written } else { f.durable };
            files.push(FileInformation {
                path: f.name.clone(),
                starting_time: NanosecondsSinceEpoch {
                    nanoseconds_since_epoch: s.start,
                },
                duration: Nanoseconds {
                    nanoseconds: s.end - s.start,
                },
                message_count: s.count,
            });
        }
        let mut total = Span::default();
        for fi in &files {
            total.merge(&Span {
                count: fi.message_count,
                start: fi.starting_time.nanoseconds_since_epoch,
                end: fi.starting_time.nanoseconds_since_epoch + fi.duration.nanoseconds,
            });
        }
        m.relative_file_paths = files.iter().map(|f| f.path.clone()).collect();
        m.files = files;
        m.message_count = total.count;
        m.starting_time.nanoseconds_since_epoch = total.start;
        m.duration.nanoseconds = total.end - total.start;
        m.topics_with_message_count = self
            .topics
            .iter()
            .map(|t| TopicWithMessageCount {
                topic_metadata: t.meta.clone(),
                message_count: if all_written { t.written } else { t.durable },
            })
            .collect();
        m
    }

    fn write_metadata(&self, sync: bool) -> Result<()> {
        self.metadata_snapshot()
            .write_dir(&self.dir, sync && self.options.sync_on_flush)?;
        Ok(())
    }
}

impl Drop for BagWriter {
    /// Finishing on drop keeps a bag valid when the owner forgets `finish()`; errors are
    /// dropped here, so call `finish()` to see them.
    fn drop(&mut self) {
        if self.closed.is_none() {
            let _ = self.finish_inner();
        }
    }
}

/// The options a writer can work with.
fn check_options(options: &WriterOptions) -> Result<()> {
    if options.flush_interval < MIN_FLUSH_INTERVAL {
        return Err(BagError::InvalidArgument(format!(
            "flush_interval {:?} is below the minimum {:?}",
            options.flush_interval, MIN_FLUSH_INTERVAL
        )));
    }
    if options.chunk_size == 0 {
        return Err(BagError::InvalidArgument("chunk_size must be > 0".into()));
    }
    Ok(())
}

/// Turn an MCAP error into a bag error; an I/O failure seen by the sink wins (it carries the
/// real OS error, e.g. ENOSPC).
fn mcap_to_bag(path: &Path, sink: &Mutex<SinkState>, e: mcap::McapError) -> BagError {
    let mut st = lock_state(sink);
    if let Some(io) = st.failure.take() {
        st.failure = Some(std::io::Error::new(io.kind(), io.to_string()));
        return BagError::Io {
            op: "write",
            path: path.to_path_buf(),
            source: io,
        };
    }
    match e {
        mcap::McapError::Io(source) => BagError::Io {
            op: "write",
            path: path.to_path_buf(),
            source,
        },
        other => BagError::Mcap {
            path: path.to_path_buf(),
            source: other,
        },
    }
}

/// Cut `path` back to `len` bytes (a record boundary after a flush) and append
/// DataEnd + Footer (no summary) + magic, making it a complete MCAP file.
pub(crate) fn seal_at(path: &Path, len: u64, sync: bool) -> Result<()> {
    let mut f = OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(io_err("open for sealing", path))?;
    f.set_len(len).map_err(io_err("truncate", path))?;
    use std::io::Seek;
    f.seek(std::io::SeekFrom::Start(len))
        .map_err(io_err("seek", path))?;
    f.write_all(&crate::mcap_tail::summaryless_tail())
        .map_err(io_err("write seal", path))?;
    if sync {
        f.sync_all().map_err(io_err("fsync", path))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recorder node moves the writer into its own task/thread.
    #[test]
    fn bag_writer_is_send() {
        fn is_send<T: Send>() {}
        is_send::<BagWriter>();
        is_send::<crate::BagReader>();
    }

    #[test]
    fn summaryless_tail_is_what_the_mcap_crate_calls_a_footer() {
        let tail = crate::mcap_tail::summaryless_tail();
        assert_eq!(tail.len(), 50);
        let mut file = mcap::MAGIC.to_vec();
        file.extend_from_slice(&tail);
        let footer = mcap::read::footer(&file).unwrap();
        assert_eq!(footer.summary_start, 0);
    }
}
