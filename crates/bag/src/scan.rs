//! Record-level scan of one MCAP file, trusting nothing: every record's length is checked
//! against the file, every chunk is decompressed and its CRC (when present) verified, every
//! inner record parsed. The scan yields the schemas, channels and *data units* (chunks and
//! loose messages) that are intact, plus the problems met, each naming file, byte offset and
//! record kind. The reader, `info` and `recover` all build on it.
//!
//! Offsets are byte offsets from the start of the file of the record's opcode byte. A problem
//! inside a chunk is reported at the chunk's offset, with the offset inside the decompressed
//! chunk in the reason.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use mcap::records::{op, Record};

use crate::error::{io_err, BagError, Result};

/// Largest chunk we agree to decompress (protects against absurd sizes in corrupt headers).
const MAX_UNCOMPRESSED_CHUNK: u64 = 4 << 30;

/// Uncompressed ÷ compressed size up to which a chunk header's claimed size is allocated at once
/// (see `decompress_chunk`).
const PLAUSIBLE_RATIO: u64 = 64;

/// Human name of an MCAP opcode.
pub fn record_kind(opcode: u8) -> &'static str {
    match opcode {
        op::HEADER => "Header",
        op::FOOTER => "Footer",
        op::SCHEMA => "Schema",
        op::CHANNEL => "Channel",
        op::MESSAGE => "Message",
        op::CHUNK => "Chunk",
        op::MESSAGE_INDEX => "MessageIndex",
        op::CHUNK_INDEX => "ChunkIndex",
        op::ATTACHMENT => "Attachment",
        op::ATTACHMENT_INDEX => "AttachmentIndex",
        op::STATISTICS => "Statistics",
        op::METADATA => "Metadata",
        op::METADATA_INDEX => "MetadataIndex",
        op::SUMMARY_OFFSET => "SummaryOffset",
        op::DATA_END => "DataEnd",
        _ => "unknown-opcode",
    }
}

#[derive(Debug, Clone)]
pub struct SchemaRec {
    pub name: String,
    pub encoding: String,
    pub data: Vec<u8>,
}

#[derive(Debug, Clone)]
pub struct ChannelRec {
    pub topic: String,
    pub schema_id: u16,
    pub message_encoding: String,
    pub metadata: BTreeMap<String, String>,
}

/// A piece of the data section that holds messages.
#[derive(Debug, Clone)]
pub struct Unit {
    /// Offset of the Chunk or Message record.
    pub offset: u64,
    pub is_chunk: bool,
    pub min_time: u64,
    pub max_time: u64,
    /// Messages per channel id.
    pub counts: BTreeMap<u16, u64>,
    /// First and last log time per channel id.
    pub times: BTreeMap<u16, (u64, u64)>,
    pub compression: String,
}

/// A message decoded from a unit.
#[derive(Debug, Clone)]
pub struct RawMessage {
    pub channel_id: u16,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: Vec<u8>,
}

#[derive(Debug, Default)]
pub struct FileScan {
    pub path: PathBuf,
    pub size: u64,
    pub profile: String,
    pub library: String,
    pub schemas: BTreeMap<u16, SchemaRec>,
    pub channels: BTreeMap<u16, ChannelRec>,
    pub units: Vec<Unit>,
    /// DataEnd, Footer and end magic are present.
    pub complete: bool,
    /// Problems in file order. With `stop_at_first`, at most one.
    pub problems: Vec<BagError>,
    /// Chunks dropped (bad CRC, bad compression, bad inner record, truncated).
    pub dropped_chunks: u64,
    /// Offset up to which the data section was intact (end of the last good record).
    pub good_until: u64,
}

fn corrupt(path: &Path, offset: u64, record: &'static str, reason: impl Into<String>) -> BagError {
    BagError::Corrupt {
        path: path.to_path_buf(),
        offset,
        record,
        reason: reason.into(),
    }
}

/// Decompress and verify a chunk body; `offset` is the chunk record's offset (for errors).
pub fn decompress_chunk(
    path: &Path,
    offset: u64,
    header: &mcap::records::ChunkHeader,
    data: &[u8],
) -> Result<Vec<u8>> {
    if header.uncompressed_size > MAX_UNCOMPRESSED_CHUNK {
        return Err(corrupt(
            path,
            offset,
            "Chunk",
            format!(
                "uncompressed size {} is implausible",
                header.uncompressed_size
            ),
        ));
    }
    // A header's size is trusted for an allocation only while it is plausible for the chunk's
    // compressed size (bag data compresses by 2–10×; a chunk of zeros by more, and takes the slow
    // path): then zstd's one-shot decoder fills a buffer of exactly that size, the fast path every
    // real bag takes. Beyond it the chunk is inflated as a stream into a vector that grows with
    // what really comes out, read no further than one byte past the claim (a chunk that inflates
    // past it is reported below) — so a corrupt size field costs no allocation of its own.
    let claimed = header.uncompressed_size;
    let plausible = claimed <= (data.len() as u64).saturating_mul(PLAUSIBLE_RATIO) + (1 << 20);
    let inflate = |reader: &mut dyn Read, what: &str| -> Result<Vec<u8>> {
        let mut v = Vec::with_capacity(if plausible {
            claimed as usize
        } else {
            data.len()
        });
        reader.take(claimed + 1).read_to_end(&mut v).map_err(|e| {
            corrupt(
                path,
                offset,
                "Chunk",
                format!("{what} decompression failed: {e}"),
            )
        })?;
        Ok(v)
    };
    let out = match header.compression.as_str() {
        "" => data.to_vec(),
        "zstd" if plausible => zstd::bulk::decompress(data, claimed as usize).map_err(|e| {
            corrupt(
                path,
                offset,
                "Chunk",
                format!("zstd decompression failed: {e}"),
            )
        })?,
        "zstd" => {
            let mut dec = zstd::stream::read::Decoder::with_buffer(data)
                .map_err(|e| corrupt(path, offset, "Chunk", format!("zstd stream invalid: {e}")))?;
            inflate(&mut dec, "zstd")?
        }
        "lz4" => {
            let mut dec = lz4::Decoder::new(data)
                .map_err(|e| corrupt(path, offset, "Chunk", format!("lz4 stream invalid: {e}")))?;
            inflate(&mut dec, "lz4")?
        }
        other => {
            return Err(corrupt(
                path,
                offset,
                "Chunk",
                format!("unsupported compression {other:?}"),
            ))
        }
    };
    if out.len() as u64 != header.uncompressed_size {
        return Err(corrupt(
            path,
            offset,
            "Chunk",
            format!(
                "decompressed to {} bytes, header says {}",
                out.len(),
                header.uncompressed_size
            ),
        ));
    }
    if header.uncompressed_crc != 0 {
        let crc = crc32fast::hash(&out);
        if crc != header.uncompressed_crc {
            return Err(corrupt(
                path,
                offset,
                "Chunk",
                format!(
                    "CRC mismatch: stored {:08x}, computed {crc:08x}",
                    header.uncompressed_crc
                ),
            ));
        }
    }
    Ok(out)
}

/// Records inside a decompressed chunk, as (offset in chunk, record).
pub fn parse_chunk_records<'a>(
    path: &Path,
    chunk_offset: u64,
    buf: &'a [u8],
) -> Result<Vec<(u64, Record<'a>)>> {
    let mut out = Vec::new();
    let mut pos = 0usize;
    while pos < buf.len() {
        if buf.len() - pos < 9 {
            return Err(corrupt(
                path,
                chunk_offset,
                "Chunk",
                format!("inner record header cut at chunk byte {pos}"),
            ));
        }
        let opcode = buf[pos];
        let len = u64::from_le_bytes(buf[pos + 1..pos + 9].try_into().expect("8 bytes"));
        let start = pos + 9;
        if len > (buf.len() - start) as u64 {
            return Err(corrupt(
                path,
                chunk_offset,
                "Chunk",
                format!(
                    "inner {} record at chunk byte {pos} claims {len} bytes, {} remain",
                    record_kind(opcode),
                    buf.len() - start
                ),
            ));
        }
        let body = &buf[start..start + len as usize];
        let rec = crate::record_layout::parse_record(opcode, body).map_err(|e| {
            corrupt(
                path,
                chunk_offset,
                "Chunk",
                format!(
                    "inner {} record at chunk byte {pos} does not parse: {e}",
                    record_kind(opcode)
                ),
            )
        })?;
        out.push((pos as u64, rec));
        pos = start + len as usize;
    }
    Ok(out)
}

/// Messages of a verified chunk.
pub fn chunk_messages(path: &Path, chunk_offset: u64, buf: &[u8]) -> Result<Vec<RawMessage>> {
    let mut v = Vec::new();
    for (_, rec) in parse_chunk_records(path, chunk_offset, buf)? {
        if let Record::Message { header, data } = rec {
            v.push(RawMessage {
                channel_id: header.channel_id,
                sequence: header.sequence,
                log_time: header.log_time,
                publish_time: header.publish_time,
                data: data.into_owned(),
            });
        }
    }
    Ok(v)
}

/// Read one top-level record (opcode, body) at `offset`, checking it lies within the file.
pub fn read_record_at(
    file: &mut File,
    path: &Path,
    offset: u64,
    file_len: u64,
) -> Result<(u8, Vec<u8>)> {
    let mut r = BufReader::new(&mut *file);
    r.seek(SeekFrom::Start(offset))
        .map_err(io_err("seek", path))?;
    read_record(&mut r, path, offset, file_len)
}

fn read_record<R: Read>(
    r: &mut R,
    path: &Path,
    offset: u64,
    file_len: u64,
) -> Result<(u8, Vec<u8>)> {
    if file_len.saturating_sub(offset) < 9 {
        return Err(corrupt(
            path,
            offset,
            "record",
            format!(
                "file ends {} bytes into a record header",
                file_len.saturating_sub(offset)
            ),
        ));
    }
    let mut h = [0u8; 9];
    r.read_exact(&mut h).map_err(io_err("read", path))?;
    let opcode = h[0];
    let len = u64::from_le_bytes(h[1..9].try_into().expect("8 bytes"));
    let avail = file_len - offset - 9;
    if len > avail {
        return Err(corrupt(
            path,
            offset,
            record_kind(opcode),
            format!("record claims {len} bytes but the file has {avail} left (truncated)"),
        ));
    }
    let mut body = vec![0u8; len as usize];
    r.read_exact(&mut body).map_err(io_err("read", path))?;
    Ok((opcode, body))
}

/// Scan `path`. With `stop_at_first`, return at the first problem (strict reading); otherwise
/// skip bad chunks/records and continue while record framing is intact.
///
/// The magic, then each record in turn (the first must be the Header; `scan_record` takes in
/// schemas, channels, messages and chunks), then the DataEnd, Footer and end magic
/// (`check_footer`).
pub fn scan_file(path: &Path, stop_at_first: bool) -> Result<FileScan> {
    let mut file = File::open(path).map_err(io_err("open", path))?;
    let size = file.metadata().map_err(io_err("stat", path))?.len();
    let mut s = FileScan {
        path: path.to_path_buf(),
        size,
        ..Default::default()
    };
    let mut r = BufReader::with_capacity(1 << 20, &mut file);
    if !starts_with_magic(&mut r, path, size, &mut s)? {
        return Ok(s);
    }
    let mut offset = 8u64;
    s.good_until = offset;
    let mut first = true;
    let mut saw_data_end = false;
    loop {
        if offset == size {
            break;
        }
        let (opcode, body) = match read_record(&mut r, path, offset, size) {
            Ok(x) => x,
            Err(e) => {
                s.problems.push(e);
                if stop_at_first || first {
                    return Ok(s);
                }
                // Framing is lost: look for the next chunk that verifies and go on from there.
                match find_next_chunk(&mut r, path, offset + 1, size)? {
                    Some(p) => {
                        s.problems.push(corrupt(
                            path,
                            offset,
                            "record",
                            format!("bytes {offset}..{p} skipped; reading resumed at a verified Chunk at offset {p}"),
                        ));
                        offset = p;
                        r.seek(SeekFrom::Start(p)).map_err(io_err("seek", path))?;
                        continue;
                    }
                    None => return Ok(s),
                }
            }
        };
        let next = offset + 9 + body.len() as u64;
        let kind = record_kind(opcode);
        let parsed = crate::record_layout::parse_record(opcode, &body);
        let rec = match parsed {
            Ok(rec) => rec,
            Err(e) => {
                s.problems
                    .push(corrupt(path, offset, kind, format!("does not parse: {e}")));
                // Framing (opcode + length) was plausible; keep going unless strict.
                if stop_at_first || opcode == op::HEADER {
                    return Ok(s);
                }
                offset = next;
                continue;
            }
        };
        if first {
            match &rec {
                Record::Header(h) => {
                    s.profile = h.profile.clone();
                    s.library = h.library.clone();
                }
                _ => {
                    s.problems
                        .push(corrupt(path, offset, kind, "first record is not a Header"));
                    return Ok(s);
                }
            }
            first = false;
            offset = next;
            s.good_until = offset;
            continue;
        }
        match scan_record(&mut s, path, offset, kind, rec, stop_at_first) {
            Scanned::Next => {}
            Scanned::DataEnd => {
                saw_data_end = true;
                s.good_until = next;
                break;
            }
            Scanned::Stop => return Ok(s),
        }
        offset = next;
        s.good_until = offset;
        if stop_at_first && !s.problems.is_empty() {
            return Ok(s);
        }
    }
    if first {
        s.problems.push(corrupt(
            path,
            8,
            "Header",
            "file ends before the Header record",
        ));
        return Ok(s);
    }
    if !saw_data_end {
        s.problems.push(corrupt(
            path,
            offset,
            "DataEnd",
            "file ends without DataEnd/Footer (recording interrupted; run recover)",
        ));
        return Ok(s);
    }
    drop(r);
    check_footer(&mut file, path, size, &mut s)?;
    Ok(s)
}

/// Whether the file starts with the MCAP magic (a problem noted when it does not).
fn starts_with_magic<R: Read>(r: &mut R, path: &Path, size: u64, s: &mut FileScan) -> Result<bool> {
    let mut magic = [0u8; 8];
    if size < 8 {
        s.problems.push(corrupt(
            path,
            0,
            "magic",
            format!("file is {size} bytes, too short for the MCAP magic"),
        ));
        return Ok(false);
    }
    r.read_exact(&mut magic).map_err(io_err("read", path))?;
    if magic != mcap::MAGIC {
        s.problems.push(corrupt(
            path,
            0,
            "magic",
            format!("not an MCAP file: starts with {magic:02x?}"),
        ));
        return Ok(false);
    }
    Ok(true)
}

/// What a record after the Header leads to.
enum Scanned {
    /// Go on with the next record.
    Next,
    /// The data section ended (DataEnd).
    DataEnd,
    /// Stop reading (a Footer before DataEnd, or a bad chunk in strict reading).
    Stop,
}

/// Take in one record after the Header at `offset`: a schema, a channel, a message outside a
/// chunk, or a chunk (its messages counted; one that does not decompress or scan dropped).
fn scan_record(
    s: &mut FileScan,
    path: &Path,
    offset: u64,
    kind: &'static str,
    rec: Record<'_>,
    stop_at_first: bool,
) -> Scanned {
    match rec {
        Record::Schema { header, data } => {
            add_schema(
                s,
                path,
                offset,
                None,
                header.id,
                header.name,
                header.encoding,
                data.into_owned(),
            );
        }
        Record::Channel(c) => add_channel(s, c),
        Record::Message { header, .. } => {
            let mut u = Unit {
                offset,
                is_chunk: false,
                min_time: header.log_time,
                max_time: header.log_time,
                counts: BTreeMap::new(),
                times: BTreeMap::new(),
                compression: String::new(),
            };
            u.counts.insert(header.channel_id, 1);
            u.times
                .insert(header.channel_id, (header.log_time, header.log_time));
            s.units.push(u);
        }
        Record::Chunk { header, data } => {
            let res = decompress_chunk(path, offset, &header, &data)
                .and_then(|buf| scan_chunk(s, path, offset, &header, &buf));
            if let Err(e) = res {
                s.dropped_chunks += 1;
                s.problems.push(e);
                if stop_at_first {
                    return Scanned::Stop;
                }
            }
        }
        Record::DataEnd(_) => return Scanned::DataEnd,
        Record::Footer(_) => {
            s.problems
                .push(corrupt(path, offset, kind, "Footer before DataEnd"));
            return Scanned::Stop;
        }
        _ => {}
    }
    Scanned::Next
}

/// The Footer (the 29-byte record right before the end magic) and the end magic after the
/// DataEnd: the scan is complete when both are there.
fn check_footer(file: &mut File, path: &Path, size: u64, s: &mut FileScan) -> Result<()> {
    let mut tail = [0u8; 37];
    if size < s.good_until + 37 {
        s.problems.push(corrupt(
            path,
            s.good_until,
            "Footer",
            "file ends before Footer and end magic",
        ));
        return Ok(());
    }
    file.seek(SeekFrom::Start(size - 37))
        .map_err(io_err("seek", path))?;
    file.read_exact(&mut tail).map_err(io_err("read", path))?;
    if &tail[29..] != mcap::MAGIC {
        s.problems
            .push(corrupt(path, size - 8, "magic", "end magic missing"));
    } else if tail[0] != op::FOOTER || u64::from_le_bytes(tail[1..9].try_into().expect("8")) != 20 {
        s.problems.push(corrupt(
            path,
            size - 37,
            "Footer",
            "Footer record not found before end magic",
        ));
    } else {
        s.complete = true;
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn add_schema(
    s: &mut FileScan,
    path: &Path,
    offset: u64,
    inner: Option<u64>,
    id: u16,
    name: String,
    encoding: String,
    data: Vec<u8>,
) {
    if encoding == "ros2msg" {
        let text = String::from_utf8_lossy(&data);
        if let Err(e) = crate::msgdef::parse_definition(&name, &text) {
            let where_ = inner
                .map(|p| format!(" (inside Chunk, chunk byte {p})"))
                .unwrap_or_default();
            let kind = if inner.is_some() { "Chunk" } else { "Schema" };
            s.problems.push(corrupt(
                path,
                offset,
                kind,
                format!("Schema {id} ({name}){where_} does not parse: {e}"),
            ));
        }
    }
    s.schemas.entry(id).or_insert(SchemaRec {
        name,
        encoding,
        data,
    });
}

fn add_channel(s: &mut FileScan, c: mcap::records::Channel) {
    s.channels.entry(c.id).or_insert(ChannelRec {
        topic: c.topic,
        schema_id: c.schema_id,
        message_encoding: c.message_encoding,
        metadata: c.metadata,
    });
}

fn scan_chunk(
    s: &mut FileScan,
    path: &Path,
    offset: u64,
    header: &mcap::records::ChunkHeader,
    buf: &[u8],
) -> Result<()> {
    let recs = parse_chunk_records(path, offset, buf)?;
    let mut u = Unit {
        offset,
        is_chunk: true,
        min_time: u64::MAX,
        max_time: 0,
        counts: BTreeMap::new(),
        times: BTreeMap::new(),
        compression: header.compression.clone(),
    };
    let mut schemas = Vec::new();
    let mut channels = Vec::new();
    for (pos, rec) in recs {
        match rec {
            Record::Schema { header, data } => schemas.push((pos, header, data.into_owned())),
            Record::Channel(c) => channels.push(c),
            Record::Message { header, .. } => {
                *u.counts.entry(header.channel_id).or_insert(0) += 1;
                let t = u
                    .times
                    .entry(header.channel_id)
                    .or_insert((header.log_time, header.log_time));
                t.0 = t.0.min(header.log_time);
                t.1 = t.1.max(header.log_time);
                u.min_time = u.min_time.min(header.log_time);
                u.max_time = u.max_time.max(header.log_time);
            }
            _ => {}
        }
    }
    for (pos, h, data) in schemas {
        add_schema(s, path, offset, Some(pos), h.id, h.name, h.encoding, data);
    }
    for c in channels {
        add_channel(s, c);
    }
    if !u.counts.is_empty() {
        s.units.push(u);
    }
    Ok(())
}

/// After lost framing, find the first offset `>= from` holding a Chunk record that is
/// self-consistent (record length = header + compressed size, known compression, nonzero CRC)
/// and whose data decompresses to a matching CRC. Chunks without CRC are not trusted here.
fn find_next_chunk<R: Read + Seek>(
    r: &mut R,
    path: &Path,
    from: u64,
    size: u64,
) -> Result<Option<u64>> {
    const WINDOW: usize = 1 << 20;
    const HEAD: usize = 9 + 8 + 8 + 8 + 4 + 4 + 4 + 8; // up to compressed_size with "zstd"
    let mut base = from;
    let mut buf = vec![0u8; WINDOW + HEAD];
    while base < size {
        let want = ((size - base) as usize).min(buf.len());
        r.seek(SeekFrom::Start(base))
            .map_err(io_err("seek", path))?;
        r.read_exact(&mut buf[..want])
            .map_err(io_err("read", path))?;
        let scan_to = want.min(WINDOW);
        for i in 0..scan_to {
            if buf[i] != op::CHUNK || want - i < HEAD - 4 {
                continue;
            }
            let h = &buf[i..want];
            let u64_at = |o: usize| u64::from_le_bytes(h[o..o + 8].try_into().expect("8"));
            let len = u64_at(1);
            let p = base + i as u64;
            if len < 44 || p + 9 + len > size {
                continue;
            }
            let (start, end) = (u64_at(9), u64_at(17));
            let crc = u32::from_le_bytes(h[33..37].try_into().expect("4"));
            let clen = u32::from_le_bytes(h[37..41].try_into().expect("4")) as usize;
            if start > end || crc == 0 || !matches!(clen, 0 | 3 | 4) || h.len() < 41 + clen + 8 {
                continue;
            }
            let comp = &h[41..41 + clen];
            if !matches!(comp, b"" | b"lz4" | b"zstd") {
                continue;
            }
            let csize = u64_at(41 + clen);
            if len != 8 + 8 + 8 + 4 + 4 + clen as u64 + 8 + csize {
                continue;
            }
            // Candidate: read and verify it fully.
            r.seek(SeekFrom::Start(p)).map_err(io_err("seek", path))?;
            let Ok((opcode, body)) = read_record(r, path, p, size) else {
                continue;
            };
            if let Ok(Record::Chunk { header, data }) =
                crate::record_layout::parse_record(opcode, &body)
            {
                if decompress_chunk(path, p, &header, &data).is_ok() {
                    return Ok(Some(p));
                }
            }
        }
        base += scan_to as u64;
        if scan_to < WINDOW {
            break;
        }
    }
    Ok(None)
}

#[cfg(test)]
mod decompress_tests {
    use super::*;

    fn header(uncompressed_size: u64) -> mcap::records::ChunkHeader {
        mcap::records::ChunkHeader {
            message_start_time: 0,
            message_end_time: 0,
            uncompressed_size,
            uncompressed_crc: 0,
            compression: "zstd".into(),
            compressed_size: 0,
        }
    }

    #[test]
    fn chunks_inflate_on_both_paths_and_a_size_claim_that_lies_is_reported() {
        let path = Path::new("test.mcap");
        // ordinary data (little to compress: xorshift bytes): the one-shot path
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let text: Vec<u8> = (0..800_000)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x >> 56) as u8
            })
            .collect();
        let packed = zstd::bulk::compress(&text, 1).unwrap();
        assert!((text.len() as u64) < packed.len() as u64 * PLAUSIBLE_RATIO);
        let out = decompress_chunk(path, 0, &header(text.len() as u64), &packed).unwrap();
        assert_eq!(out, text);
        // 16 MiB of zeros pack into a few hundred bytes: beyond the plausible ratio, streamed
        let zeros = vec![0u8; 16 << 20];
        let packed = zstd::bulk::compress(&zeros, 1).unwrap();
        assert!(zeros.len() as u64 > packed.len() as u64 * PLAUSIBLE_RATIO + (1 << 20));
        let out = decompress_chunk(path, 0, &header(zeros.len() as u64), &packed).unwrap();
        assert_eq!(out.len(), zeros.len());
        // a header claiming 1 GiB for those bytes: streamed, and the mismatch named
        let e = decompress_chunk(path, 0, &header(1 << 30), &packed).unwrap_err();
        assert!(e.to_string().contains("header says 1073741824"), "{e}");
        // a claim smaller than what comes out is refused (the one-shot decoder's buffer is full)
        assert!(decompress_chunk(path, 0, &header(1000), &packed).is_err());
    }
}
