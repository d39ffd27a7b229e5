//! [`BagReader`]: opens a rosbag2 directory (through metadata.yaml) or a single `.mcap` file,
//! lists topics and iterates messages in log-time order across files.
//!
//! Ordering: messages come out by ascending log time; equal log times keep file order
//! (file index, then position in the file). Memory stays bounded by the chunks whose time
//! ranges overlap the current read position.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::fs::File;
use std::path::{Path, PathBuf};

use mcap::records::Record;

use crate::error::{io_err, BagError, Result};
use crate::metadata::{BagMetadata, METADATA_FILE};
use crate::scan::{
    chunk_messages, decompress_chunk, read_record_at, scan_file, FileScan, RawMessage,
};

/// How to treat damaged input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReadMode {
    /// The first problem is an error from `open` (naming file, offset, record kind).
    #[default]
    Strict,
    /// Skip bad chunks/records, keep everything readable, list problems in
    /// [`BagReader::problems`].
    Tolerant,
}

/// One topic of the bag (merged over files by name).
#[derive(Debug, Clone, PartialEq)]
pub struct TopicInfo {
    pub name: String,
    /// `pkg/msg/Type`.
    pub type_name: String,
    /// Schema encoding (`ros2msg`) and text.
    pub schema_encoding: String,
    pub definition: String,
    pub message_encoding: String,
    pub offered_qos_profiles: String,
    pub type_description_hash: String,
    pub message_count: u64,
    /// First / last log time (ns) of its messages, if any.
    pub first_time: Option<u64>,
    pub last_time: Option<u64>,
}

/// A message read from the bag.
#[derive(Debug, Clone, PartialEq)]
pub struct BagMessage {
    /// Index into [`BagReader::topics`].
    pub topic_index: usize,
    pub topic: String,
    pub log_time: u64,
    pub publish_time: u64,
    pub sequence: u32,
    /// CDR bytes including the 4-byte encapsulation header.
    pub data: Vec<u8>,
}

/// Which messages to iterate.
#[derive(Debug, Clone, Default)]
pub struct MessageFilter {
    /// Topic names to keep; `None` keeps all.
    pub topics: Option<Vec<String>>,
    /// Keep log times `>= start_ns`.
    pub start_ns: Option<u64>,
    /// Keep log times `< end_ns`.
    pub end_ns: Option<u64>,
}

pub(crate) struct OpenedFile {
    pub scan: FileScan,
    /// MCAP channel id → topic index.
    pub channel_topic: HashMap<u16, usize>,
}

/// Reader of a bag directory or a single MCAP file.
pub struct BagReader {
    path: PathBuf,
    pub(crate) metadata: Option<BagMetadata>,
    pub(crate) files: Vec<OpenedFile>,
    topics: Vec<TopicInfo>,
    problems: Vec<BagError>,
}

/// The .mcap files of a bag path: the files listed in metadata.yaml for a directory that has
/// one, else the directory's `*.mcap` files in name order, else the path itself.
pub(crate) fn bag_files(path: &Path) -> Result<(Vec<PathBuf>, Option<BagMetadata>)> {
    if !path.exists() {
        // even a tolerant reader has nothing to report on: no bag is there at all
        return Err(BagError::InvalidArgument(format!("no bag at {}: no such file or directory (a bag is a rosbag2 directory or an .mcap file)", path.display())));
    }
    if path.is_dir() {
        if path.join(METADATA_FILE).exists() {
            let m = BagMetadata::read_dir(path)?;
            if m.storage_identifier != "mcap" {
                return Err(BagError::Metadata {
                    path: path.join(METADATA_FILE),
                    reason: format!(
                        "storage_identifier is {:?}, only \"mcap\" is supported",
                        m.storage_identifier
                    ),
                });
            }
            let files = m
                .relative_file_paths
                .iter()
                .map(|p| path.join(Path::new(p).file_name().unwrap_or_default()))
                .collect();
            return Ok((files, Some(m)));
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .map_err(io_err("list", path))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
            .collect();
        files.sort_by_key(|p| split_index(p));
        if files.is_empty() {
            return Err(BagError::InvalidArgument(format!(
                "{} holds no metadata.yaml and no .mcap file",
                path.display()
            )));
        }
        return Ok((files, None));
    }
    Ok((vec![path.to_path_buf()], None))
}

/// Sort key for `<name>_<N>.mcap`: (N, name).
fn split_index(p: &Path) -> (u64, String) {
    let stem = p
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("")
        .to_string();
    let n = stem
        .rsplit('_')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    (n, stem)
}

impl BagReader {
    /// Open strictly (any damage is an error, [`BagError::Damaged`], which names the damage and
    /// tells the user to run `metrocell bag recover`).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Self::open_with(path.as_ref(), ReadMode::Strict).map_err(|e| e.in_bag(path.as_ref()))
    }

    pub fn open_with(path: impl AsRef<Path>, mode: ReadMode) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        let (paths, metadata) = bag_files(&path)?;
        let mut files = Vec::new();
        let mut problems = Vec::new();
        for p in &paths {
            if !p.exists() && mode == ReadMode::Tolerant {
                problems.push(BagError::Io {
                    op: "open",
                    path: p.clone(),
                    source: std::io::Error::from(std::io::ErrorKind::NotFound),
                });
                continue;
            }
            let scan = scan_file(p, mode == ReadMode::Strict)?;
            if mode == ReadMode::Strict {
                if let Some(e) = scan.problems.into_iter().next() {
                    return Err(e);
                }
                files.push(OpenedFile {
                    scan: FileScan {
                        problems: Vec::new(),
                        ..scan
                    },
                    channel_topic: HashMap::new(),
                });
            } else {
                let mut scan = scan;
                problems.append(&mut scan.problems);
                files.push(OpenedFile {
                    scan,
                    channel_topic: HashMap::new(),
                });
            }
        }
        let mut topics: Vec<TopicInfo> = Vec::new();
        let mut by_name: HashMap<String, usize> = HashMap::new();
        for f in &mut files {
            for (&cid, ch) in &f.scan.channels {
                let schema = f.scan.schemas.get(&ch.schema_id);
                let idx = *by_name.entry(ch.topic.clone()).or_insert_with(|| {
                    topics.push(TopicInfo {
                        name: ch.topic.clone(),
                        type_name: schema.map(|s| s.name.clone()).unwrap_or_default(),
                        schema_encoding: schema.map(|s| s.encoding.clone()).unwrap_or_default(),
                        definition: schema
                            .map(|s| String::from_utf8_lossy(&s.data).into_owned())
                            .unwrap_or_default(),
                        message_encoding: ch.message_encoding.clone(),
                        offered_qos_profiles: ch
                            .metadata
                            .get("offered_qos_profiles")
                            .cloned()
                            .unwrap_or_default(),
                        type_description_hash: ch
                            .metadata
                            .get("topic_type_hash")
                            .cloned()
                            .unwrap_or_default(),
                        message_count: 0,
                        first_time: None,
                        last_time: None,
                    });
                    topics.len() - 1
                });
                f.channel_topic.insert(cid, idx);
            }
            for u in &f.scan.units {
                for (cid, n) in &u.counts {
                    let Some(&ti) = f.channel_topic.get(cid) else {
                        let e = BagError::Corrupt {
                            path: f.scan.path.clone(),
                            offset: u.offset,
                            record: if u.is_chunk { "Chunk" } else { "Message" },
                            reason: format!(
                                "{n} message(s) on channel {cid}, which no Channel record defines"
                            ),
                        };
                        if mode == ReadMode::Strict {
                            return Err(e);
                        }
                        problems.push(e);
                        continue;
                    };
                    let t = &mut topics[ti];
                    t.message_count += n;
                    let (a, b) = u.times[cid];
                    t.first_time = Some(t.first_time.map_or(a, |x| x.min(a)));
                    t.last_time = Some(t.last_time.map_or(b, |x| x.max(b)));
                }
            }
        }
        // Topics declared in metadata.yaml but absent from the files (no messages yet).
        if let Some(m) = &metadata {
            for t in &m.topics_with_message_count {
                if !by_name.contains_key(&t.topic_metadata.name) {
                    by_name.insert(t.topic_metadata.name.clone(), topics.len());
                    topics.push(TopicInfo {
                        name: t.topic_metadata.name.clone(),
                        type_name: t.topic_metadata.type_name.clone(),
                        schema_encoding: String::new(),
                        definition: String::new(),
                        message_encoding: t.topic_metadata.serialization_format.clone(),
                        offered_qos_profiles: t.topic_metadata.offered_qos_profiles.clone(),
                        type_description_hash: t.topic_metadata.type_description_hash.clone(),
                        message_count: 0,
                        first_time: None,
                        last_time: None,
                    });
                }
            }
        }
        Ok(Self {
            path,
            metadata,
            files,
            topics,
            problems,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// metadata.yaml contents, when the bag is a directory that has one.
    pub fn metadata(&self) -> Option<&BagMetadata> {
        self.metadata.as_ref()
    }

    pub fn topics(&self) -> &[TopicInfo] {
        &self.topics
    }

    pub fn topic(&self, name: &str) -> Option<&TopicInfo> {
        self.topics.iter().find(|t| t.name == name)
    }

    /// Problems skipped in tolerant mode (empty in strict mode).
    pub fn problems(&self) -> &[BagError] {
        &self.problems
    }

    /// The MCAP files read, in order.
    pub fn files(&self) -> Vec<&Path> {
        self.files.iter().map(|f| f.scan.path.as_path()).collect()
    }

    pub(crate) fn scans(&self) -> impl Iterator<Item = &FileScan> {
        self.files.iter().map(|f| &f.scan)
    }

    pub fn message_count(&self) -> u64 {
        self.topics.iter().map(|t| t.message_count).sum()
    }

    /// What `metrocell bag info` prints, from this reader (no second open or scan).
    pub fn info(&self) -> crate::info::BagInfo {
        crate::info::info_from_reader(self)
    }

    /// Iterate messages in log-time order.
    pub fn messages(&self, filter: &MessageFilter) -> Result<MessageIter<'_>> {
        let wanted: Option<Vec<usize>> = match &filter.topics {
            None => None,
            Some(names) => {
                let mut v = Vec::new();
                for n in names {
                    match self.topics.iter().position(|t| &t.name == n) {
                        Some(i) => v.push(i),
                        None => {
                            return Err(BagError::InvalidArgument(format!(
                                "topic {n} is not in bag {}",
                                self.path.display()
                            )))
                        }
                    }
                }
                Some(v)
            }
        };
        let start = filter.start_ns.unwrap_or(0);
        let end = filter.end_ns.unwrap_or(u64::MAX);
        let mut units = Vec::new();
        for (fi, f) in self.files.iter().enumerate() {
            for (ui, u) in f.scan.units.iter().enumerate() {
                if u.max_time < start || u.min_time >= end {
                    continue;
                }
                let relevant = u.counts.keys().any(|cid| {
                    f.channel_topic
                        .get(cid)
                        .is_some_and(|ti| wanted.as_ref().map_or(true, |w| w.contains(ti)))
                });
                if relevant {
                    units.push((u.min_time, fi, ui));
                }
            }
        }
        units.sort();
        let handles = self
            .files
            .iter()
            .map(|f| File::open(&f.scan.path).map_err(io_err("open", &f.scan.path)))
            .collect::<Result<Vec<_>>>()?;
        Ok(MessageIter {
            reader: self,
            wanted,
            start,
            end,
            units,
            next_unit: 0,
            heap: BinaryHeap::new(),
            counter: 0,
            handles,
        })
    }

    /// All messages, log-time order, collected (convenience for small bags and tests).
    pub fn read_all(&self, filter: &MessageFilter) -> Result<Vec<BagMessage>> {
        self.messages(filter)?.collect()
    }
}

/// Heap entry ordered by (log_time, load order).
struct Pending {
    key: (u64, u64),
    topic_index: usize,
    msg: RawMessage,
}
impl PartialEq for Pending {
    fn eq(&self, o: &Self) -> bool {
        self.key == o.key
    }
}
impl Eq for Pending {}
impl PartialOrd for Pending {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Pending {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.key.cmp(&o.key)
    }
}

/// Iterator over messages in log-time order; see [`BagReader::messages`].
pub struct MessageIter<'a> {
    reader: &'a BagReader,
    wanted: Option<Vec<usize>>,
    start: u64,
    end: u64,
    units: Vec<(u64, usize, usize)>,
    next_unit: usize,
    heap: BinaryHeap<Reverse<Pending>>,
    counter: u64,
    handles: Vec<File>,
}

impl MessageIter<'_> {
    fn load(&mut self, fi: usize, ui: usize) -> Result<()> {
        let f = &self.reader.files[fi];
        let u = &f.scan.units[ui];
        let path = &f.scan.path;
        let (opcode, body) = read_record_at(&mut self.handles[fi], path, u.offset, f.scan.size)?;
        let rec =
            crate::record_layout::parse_record(opcode, &body).map_err(|e| BagError::Corrupt {
                path: path.clone(),
                offset: u.offset,
                record: crate::scan::record_kind(opcode),
                reason: format!("changed since open: {e}"),
            })?;
        let msgs = match rec {
            Record::Chunk { header, data } => {
                let buf = decompress_chunk(path, u.offset, &header, &data)?;
                chunk_messages(path, u.offset, &buf)?
            }
            Record::Message { header, data } => vec![RawMessage {
                channel_id: header.channel_id,
                sequence: header.sequence,
                log_time: header.log_time,
                publish_time: header.publish_time,
                data: data.into_owned(),
            }],
            _ => Vec::new(),
        };
        for m in msgs {
            if m.log_time < self.start || m.log_time >= self.end {
                continue;
            }
            let Some(&ti) = f.channel_topic.get(&m.channel_id) else {
                continue;
            };
            if self.wanted.as_ref().is_some_and(|w| !w.contains(&ti)) {
                continue;
            }
            self.counter += 1;
            self.heap.push(Reverse(Pending {
                key: (m.log_time, self.counter),
                topic_index: ti,
                msg: m,
            }));
        }
        Ok(())
    }
}

impl Iterator for MessageIter<'_> {
    type Item = Result<BagMessage>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let load_next = self.next_unit < self.units.len()
                && self
                    .heap
                    .peek()
                    .map_or(true, |Reverse(p)| self.units[self.next_unit].0 <= p.key.0);
            if load_next {
                let (_, fi, ui) = self.units[self.next_unit];
                self.next_unit += 1;
                if let Err(e) = self.load(fi, ui) {
                    self.next_unit = self.units.len();
                    self.heap.clear();
                    return Some(Err(e.in_bag(&self.reader.path)));
                }
                continue;
            }
            let Reverse(p) = self.heap.pop()?;
            return Some(Ok(BagMessage {
                topic_index: p.topic_index,
                topic: self.reader.topics[p.topic_index].name.clone(),
                log_time: p.msg.log_time,
                publish_time: p.msg.publish_time,
                sequence: p.msg.sequence,
                data: p.msg.data,
            }));
        }
    }
}
