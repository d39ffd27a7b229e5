//! [`info`]: a summary of a bag in the spirit of `ros2 bag info`.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::error::Result;
use crate::metadata::{
    BagMetadata, FileInformation, Nanoseconds, NanosecondsSinceEpoch, TopicMetadata,
    TopicWithMessageCount,
};
use crate::reader::{BagReader, ReadMode};

#[derive(Debug, Clone, PartialEq)]
pub struct TopicSummary {
    pub name: String,
    pub type_name: String,
    pub serialization_format: String,
    pub message_count: u64,
    /// Mean rate over the topic's own first..last message (count-1)/(last-first), in Hz;
    /// `None` for fewer than two messages.
    pub rate_hz: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct FileSummary {
    pub path: PathBuf,
    pub size_bytes: u64,
    pub message_count: u64,
    /// Has DataEnd + Footer + end magic (closed cleanly or sealed).
    pub complete: bool,
}

/// What `info` reports. Times are ns since the Unix epoch (log time).
#[derive(Debug, Clone, PartialEq)]
pub struct BagInfo {
    pub path: PathBuf,
    pub storage_identifier: String,
    pub files: Vec<FileSummary>,
    pub size_bytes: u64,
    /// Chunk compressions found (`zstd`, `lz4`, `` for none), sorted, deduplicated.
    pub compression: Vec<String>,
    pub message_count: u64,
    pub start_ns: Option<u64>,
    pub end_ns: Option<u64>,
    pub duration_ns: u64,
    pub topics: Vec<TopicSummary>,
    /// Damage found (the bag was read tolerantly); empty for a healthy bag.
    pub problems: Vec<String>,
}

/// Summarise the bag at `path` (directory or .mcap file). Damage does not fail `info`; it is
/// listed in [`BagInfo::problems`].
pub fn info(path: impl AsRef<Path>) -> Result<BagInfo> {
    let r = BagReader::open_with(path.as_ref(), ReadMode::Tolerant)?;
    Ok(info_from_reader(&r))
}

pub(crate) fn info_from_reader(r: &BagReader) -> BagInfo {
    let mut files = Vec::new();
    let mut compression: Vec<String> = Vec::new();
    for s in r.scans() {
        let count = s.units.iter().map(|u| u.counts.values().sum::<u64>()).sum();
        files.push(FileSummary {
            path: s.path.clone(),
            size_bytes: s.size,
            message_count: count,
            complete: s.complete,
        });
        for u in s.units.iter().filter(|u| u.is_chunk) {
            if !compression.contains(&u.compression) {
                compression.push(u.compression.clone());
            }
        }
    }
    compression.sort();
    let topics: Vec<TopicSummary> = r
        .topics()
        .iter()
        .map(|t| TopicSummary {
            name: t.name.clone(),
            type_name: t.type_name.clone(),
            serialization_format: t.message_encoding.clone(),
            message_count: t.message_count,
            rate_hz: match (t.first_time, t.last_time) {
                (Some(a), Some(b)) if t.message_count > 1 && b > a => {
                    Some((t.message_count - 1) as f64 / ((b - a) as f64 * 1e-9))
                }
                _ => None,
            },
        })
        .collect();
    let start_ns = r.topics().iter().filter_map(|t| t.first_time).min();
    let end_ns = r.topics().iter().filter_map(|t| t.last_time).max();
    BagInfo {
        path: r.path().to_path_buf(),
        storage_identifier: "mcap".into(),
        size_bytes: files.iter().map(|f| f.size_bytes).sum(),
        files,
        compression,
        message_count: r.message_count(),
        start_ns,
        end_ns,
        duration_ns: match (start_ns, end_ns) {
            (Some(a), Some(b)) => b - a,
            _ => 0,
        },
        topics,
        problems: r.problems().iter().map(|p| p.to_string()).collect(),
    }
}

/// rosbag2 metadata describing what a reader found in the files (used by `recover`).
pub(crate) fn metadata_from_reader(r: &BagReader) -> BagMetadata {
    let mut m = BagMetadata::empty();
    for s in r.scans() {
        let name = s
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut count = 0;
        let mut start = u64::MAX;
        let mut end = 0;
        for u in &s.units {
            count += u.counts.values().sum::<u64>();
            start = start.min(u.min_time);
            end = end.max(u.max_time);
        }
        if count == 0 {
            start = 0;
        }
        m.relative_file_paths.push(name.clone());
        m.files.push(FileInformation {
            path: name,
            starting_time: NanosecondsSinceEpoch {
                nanoseconds_since_epoch: start,
            },
            duration: Nanoseconds {
                nanoseconds: end.saturating_sub(start),
            },
            message_count: count,
        });
    }
    let i = info_from_reader(r);
    m.message_count = i.message_count;
    m.starting_time.nanoseconds_since_epoch = i.start_ns.unwrap_or(0);
    m.duration.nanoseconds = i.duration_ns;
    m.topics_with_message_count = r
        .topics()
        .iter()
        .map(|t| TopicWithMessageCount {
            topic_metadata: TopicMetadata {
                name: t.name.clone(),
                type_name: t.type_name.clone(),
                serialization_format: t.message_encoding.clone(),
                offered_qos_profiles: t.offered_qos_profiles.clone(),
                type_description_hash: t.type_description_hash.clone(),
            },
            message_count: t.message_count,
        })
        .collect();
    m
}

/// `YYYY-MM-DD hh:mm:ss.nnnnnnnnn` UTC of a ns timestamp (civil-from-days, proleptic
/// Gregorian).
pub fn format_utc(ns: u64) -> String {
    let secs = ns / 1_000_000_000;
    let nanos = ns % 1_000_000_000;
    let days = (secs / 86_400) as i64;
    let sod = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02}.{nanos:09}",
        sod / 3600,
        (sod / 60) % 60,
        sod % 60
    )
}

fn human_size(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut i = 0;
    while v >= 1024.0 && i + 1 < units.len() {
        v /= 1024.0;
        i += 1;
    }
    if i == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", units[i])
    }
}

impl fmt::Display for BagInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const W: usize = 19;
        for (i, file) in self.files.iter().enumerate() {
            let label = if i == 0 { "Files:" } else { "" };
            let name = file
                .path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let flag = if file.complete {
                ""
            } else {
                "  (incomplete: run `metrocell bag recover`)"
            };
            writeln!(f, "{label:<W$}{name}{flag}")?;
        }
        writeln!(f, "{:<W$}{}", "Bag size:", human_size(self.size_bytes))?;
        writeln!(f, "{:<W$}{}", "Storage id:", self.storage_identifier)?;
        let comp = if self.compression.is_empty() {
            "none".to_string()
        } else {
            self.compression
                .iter()
                .map(|c| if c.is_empty() { "none" } else { c.as_str() })
                .collect::<Vec<_>>()
                .join(", ")
        };
        writeln!(f, "{:<W$}{comp} (chunk)", "Compression:")?;
        writeln!(
            f,
            "{:<W$}{}.{:09}s",
            "Duration:",
            self.duration_ns / 1_000_000_000,
            self.duration_ns % 1_000_000_000
        )?;
        if let (Some(s), Some(e)) = (self.start_ns, self.end_ns) {
            writeln!(
                f,
                "{:<W$}{} UTC ({}.{:09})",
                "Start:",
                format_utc(s),
                s / 1_000_000_000,
                s % 1_000_000_000
            )?;
            writeln!(
                f,
                "{:<W$}{} UTC ({}.{:09})",
                "End:",
                format_utc(e),
                e / 1_000_000_000,
                e % 1_000_000_000
            )?;
        }
        writeln!(f, "{:<W$}{}", "Messages:", self.message_count)?;
        let name_w = self.topics.iter().map(|t| t.name.len()).max().unwrap_or(0);
        let type_w = self
            .topics
            .iter()
            .map(|t| t.type_name.len())
            .max()
            .unwrap_or(0);
        for (i, t) in self.topics.iter().enumerate() {
            let label = if i == 0 { "Topic information:" } else { "" };
            let rate = t
                .rate_hz
                .map(|r| format!("{r:.3} Hz"))
                .unwrap_or_else(|| "-".into());
            writeln!(
                f,
                "{label:<W$}Topic: {:<name_w$} | Type: {:<type_w$} | Count: {} | Rate: {rate} | Serialization Format: {}",
                t.name, t.type_name, t.message_count, t.serialization_format
            )?;
        }
        for p in &self.problems {
            writeln!(f, "{:<W$}{p}", "Problem:")?;
        }
        if !self.problems.is_empty() {
            writeln!(
                f,
                "{:<W$}the counts above are what is readable; strict readers (calibrate, diagnose, bag export, ...) refuse this bag: \
                 run `metrocell bag recover {}`, which rebuilds it from every chunk that reached the disk intact",
                "Next step:",
                self.path.display()
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_formatting_matches_known_dates() {
        assert_eq!(format_utc(0), "1970-01-01 00:00:00.000000000");
        // 2000-02-29 12:34:56.789 UTC = 951827696.789 s
        assert_eq!(
            format_utc(951_827_696_789_000_000),
            "2000-02-29 12:34:56.789000000"
        );
        assert_eq!(
            format_utc(1_763_767_681_000_000_001),
            "2025-11-21 23:28:01.000000001"
        );
    }
}
