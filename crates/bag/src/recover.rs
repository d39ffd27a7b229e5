//! [`recover`]: rebuild a valid bag from MCAP files cut at an arbitrary byte, left without
//! summary/footer by `kill -9`, or damaged inside.
//!
//! Per file: scan from the start ([`crate::scan`]); keep every message of every complete chunk
//! whose CRC verifies (chunks written without CRC are kept when they decompress to exactly
//! their stated size and every inner record parses) and every complete un-chunked message;
//! stop at the first record whose framing is broken (nothing after it can be trusted to be
//! aligned). The kept messages are written, in their original order, with their original
//! schemas and channels, to a new MCAP file that replaces the damaged one (the original is
//! kept as `<file>.orig` unless told otherwise). A file that is already complete and sound is
//! left untouched. Finally metadata.yaml is rebuilt from the files.

use std::collections::{BTreeMap, HashMap};
use std::fs::OpenOptions;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::records::Record;

use crate::error::{io_err, BagError, Result};
use crate::info::metadata_from_reader;
use crate::metadata::METADATA_FILE;
use crate::reader::{BagReader, ReadMode};
use crate::scan::{chunk_messages, decompress_chunk, read_record_at, scan_file, RawMessage};

#[derive(Debug, Clone)]
pub struct RecoverOptions {
    /// Keep each rewritten original as `<file>.orig` (and `metadata.yaml.orig`).
    pub keep_original: bool,
}

impl Default for RecoverOptions {
    fn default() -> Self {
        Self {
            keep_original: true,
        }
    }
}

/// What happened to one file.
#[derive(Debug, Clone, PartialEq)]
pub struct FileRecovery {
    pub path: PathBuf,
    /// The file was complete and sound and was left as is.
    pub untouched: bool,
    /// Where the original went, if it was rewritten and kept.
    pub original_kept_as: Option<PathBuf>,
    pub kept_messages: u64,
    /// Messages known to be dropped (e.g. on channels with no Channel record). Messages in a
    /// dropped chunk cannot always be counted; see `dropped_chunks` and `dropped_bytes`.
    pub dropped_messages: u64,
    pub dropped_chunks: u64,
    /// Bytes after the last intact record (a torn tail).
    pub dropped_bytes: u64,
    /// Why things were dropped: each names offset and record kind.
    pub reasons: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RecoveryReport {
    pub files: Vec<FileRecovery>,
    /// metadata.yaml written (bag directories only).
    pub metadata_path: Option<PathBuf>,
}

impl RecoveryReport {
    pub fn kept_messages(&self) -> u64 {
        self.files.iter().map(|f| f.kept_messages).sum()
    }
    pub fn dropped_chunks(&self) -> u64 {
        self.files.iter().map(|f| f.dropped_chunks).sum()
    }
}

impl std::fmt::Display for RecoveryReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for r in &self.files {
            if r.untouched {
                writeln!(
                    f,
                    "{}: intact, {} messages",
                    r.path.display(),
                    r.kept_messages
                )?;
            } else {
                writeln!(
                    f,
                    "{}: rewritten, kept {} messages, dropped {} chunk(s), {} message(s), {} trailing byte(s)",
                    r.path.display(),
                    r.kept_messages,
                    r.dropped_chunks,
                    r.dropped_messages,
                    r.dropped_bytes
                )?;
            }
            for why in &r.reasons {
                writeln!(f, "  {why}")?;
            }
        }
        if let Some(m) = &self.metadata_path {
            writeln!(f, "wrote {}", m.display())?;
        }
        Ok(())
    }
}

pub fn recover(path: impl AsRef<Path>) -> Result<RecoveryReport> {
    recover_with(path, &RecoverOptions::default())
}

/// Recover a bag directory (all `.mcap` files listed in metadata.yaml or present) or a single
/// `.mcap` file, in place.
pub fn recover_with(path: impl AsRef<Path>, options: &RecoverOptions) -> Result<RecoveryReport> {
    let path = path.as_ref();
    let files = if path.is_dir() {
        let mut set: Vec<PathBuf> = Vec::new();
        if path.join(METADATA_FILE).exists() {
            if let Ok((listed, _)) = crate::reader::bag_files(path) {
                set.extend(listed.into_iter().filter(|p| p.exists()));
            }
        }
        for e in std::fs::read_dir(path).map_err(io_err("list", path))? {
            let p = e.map_err(io_err("list", path))?.path();
            if p.extension().is_some_and(|x| x == "mcap") && !set.contains(&p) {
                set.push(p);
            }
        }
        set.sort_by_key(|p| {
            let stem = p
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("")
                .to_string();
            (
                stem.rsplit('_')
                    .next()
                    .and_then(|n| n.parse::<u64>().ok())
                    .unwrap_or(0),
                stem,
            )
        });
        set
    } else {
        vec![path.to_path_buf()]
    };
    let mut report = RecoveryReport {
        files: Vec::new(),
        metadata_path: None,
    };
    for f in &files {
        report.files.push(recover_file(f, options)?);
    }
    if path.is_dir() {
        let meta = path.join(METADATA_FILE);
        if meta.exists() {
            if options.keep_original {
                std::fs::rename(&meta, path.join("metadata.yaml.orig"))
                    .map_err(io_err("rename", &meta))?;
            } else {
                std::fs::remove_file(&meta).map_err(io_err("remove", &meta))?;
            }
        }
        // Without metadata.yaml the reader takes the directory's .mcap files in split order.
        let reader = BagReader::open_with(path, ReadMode::Strict)?;
        let m = metadata_from_reader(&reader);
        report.metadata_path = Some(m.write_dir(path, true)?);
    }
    Ok(report)
}

fn recover_file(path: &Path, options: &RecoverOptions) -> Result<FileRecovery> {
    let scan = scan_file(path, false)?;
    let mut rep = FileRecovery {
        path: path.to_path_buf(),
        untouched: false,
        original_kept_as: None,
        kept_messages: 0,
        dropped_messages: 0,
        dropped_chunks: scan.dropped_chunks,
        dropped_bytes: scan.size.saturating_sub(scan.good_until),
        reasons: scan.problems.iter().map(|p| p.to_string()).collect(),
    };
    let total: u64 = scan
        .units
        .iter()
        .map(|u| u.counts.values().sum::<u64>())
        .sum();
    if scan.complete && scan.problems.is_empty() {
        rep.untouched = true;
        rep.kept_messages = total;
        rep.dropped_bytes = 0;
        return Ok(rep);
    }
    if scan.profile.is_empty() && scan.units.is_empty() && scan.schemas.is_empty() {
        // Not even a Header: write an empty but valid file so the bag opens.
        rep.reasons
            .push("no intact records; the rewritten file holds no messages".into());
    }
    let tmp = path.with_extension("mcap.recovering");
    let out = OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&tmp)
        .map_err(io_err("create", &tmp))?;
    let compression = scan
        .units
        .iter()
        .find(|u| u.is_chunk)
        .map(|u| u.compression.clone())
        .unwrap_or_else(|| "zstd".into());
    let mut w = mcap::WriteOptions::new()
        .profile(if scan.profile.is_empty() {
            "ros2".to_string()
        } else {
            scan.profile.clone()
        })
        .library(format!("{} (recovered)", crate::writer::LIBRARY))
        .compression(match compression.as_str() {
            "lz4" => Some(mcap::Compression::Lz4),
            "" => None,
            _ => Some(mcap::Compression::Zstd),
        })
        .compression_threads(0)
        .create(BufWriter::new(out))
        .map_err(|e| BagError::Mcap {
            path: tmp.clone(),
            source: e,
        })?;
    let mcap_err = |e| BagError::Mcap {
        path: tmp.clone(),
        source: e,
    };
    let mut schema_map: HashMap<u16, u16> = HashMap::new();
    for (&id, s) in &scan.schemas {
        schema_map.insert(
            id,
            w.add_schema(&s.name, &s.encoding, &s.data)
                .map_err(mcap_err)?,
        );
    }
    let mut channel_map: BTreeMap<u16, u16> = BTreeMap::new();
    for (&id, c) in &scan.channels {
        let sid = schema_map.get(&c.schema_id).copied().unwrap_or(0);
        channel_map.insert(
            id,
            w.add_channel(sid, &c.topic, &c.message_encoding, &c.metadata)
                .map_err(mcap_err)?,
        );
    }
    let mut file = std::fs::File::open(path).map_err(io_err("open", path))?;
    for u in &scan.units {
        let (opcode, body) = read_record_at(&mut file, path, u.offset, scan.size)?;
        let msgs: Vec<RawMessage> = match crate::record_layout::parse_record(opcode, &body) {
            Ok(Record::Chunk { header, data }) => {
                let buf = decompress_chunk(path, u.offset, &header, &data)?;
                chunk_messages(path, u.offset, &buf)?
            }
            Ok(Record::Message { header, data }) => vec![RawMessage {
                channel_id: header.channel_id,
                sequence: header.sequence,
                log_time: header.log_time,
                publish_time: header.publish_time,
                data: data.into_owned(),
            }],
            _ => Vec::new(),
        };
        for m in msgs {
            let Some(&cid) = channel_map.get(&m.channel_id) else {
                rep.dropped_messages += 1;
                continue;
            };
            let h = mcap::records::MessageHeader {
                channel_id: cid,
                sequence: m.sequence,
                log_time: m.log_time,
                publish_time: m.publish_time,
            };
            w.write_to_known_channel(&h, &m.data).map_err(mcap_err)?;
            rep.kept_messages += 1;
        }
    }
    if rep.dropped_messages > 0 {
        rep.reasons.push(format!(
            "{} message(s) referenced channels with no Channel record",
            rep.dropped_messages
        ));
    }
    w.finish().map_err(mcap_err)?;
    let inner = w.into_inner();
    let file_out = inner.into_inner().map_err(|e| BagError::Io {
        op: "flush",
        path: tmp.clone(),
        source: e.into_error(),
    })?;
    file_out.sync_all().map_err(io_err("fsync", &tmp))?;
    drop(file_out);
    if options.keep_original {
        let orig = PathBuf::from(format!("{}.orig", path.display()));
        std::fs::rename(path, &orig).map_err(io_err("rename", path))?;
        rep.original_kept_as = Some(orig);
    }
    std::fs::rename(&tmp, path).map_err(io_err("rename", &tmp))?;
    Ok(rep)
}
