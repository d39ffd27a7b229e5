//! Every length field of an MCAP record checked against the record before the `mcap` crate
//! parses it. Its parser (binrw) allocates what a string's or a map's length prefix claims
//! before it finds the bytes are not there: a corrupt Chunk header whose compression-string
//! length read 1.45 GB had it allocate 1.45 GB for a 3-KiB record (found by the fuzz harnesses'
//! memory limit, tests/fuzz). Here a length that runs past its record is an error naming the
//! field, and nothing is allocated for it.
//!
//! Layouts per the MCAP specification (Records): `str` is a uint32 byte length and UTF-8,
//! `bytes4`/`bytes8` a uint32/uint64 byte length and the bytes, maps and arrays a uint32 byte
//! length of their entries; Message data runs to the record's end.

use mcap::records::{op, Record};

/// One field of a record's layout.
#[derive(Clone, Copy)]
enum Field {
    Fixed(usize),
    /// uint32 length and that many bytes (a string, Schema data, a byte array).
    Bytes4,
    /// uint64 length and that many bytes (Chunk records, Attachment data).
    Bytes8,
    /// uint32 byte length of (str, str) entries.
    StringMap,
    /// uint32 byte length of fixed-size entries.
    FixedArray(usize),
    /// The rest of the record.
    Rest,
}

use Field::*;

fn layout(opcode: u8) -> Option<&'static [Field]> {
    Some(match opcode {
        op::HEADER => &[Bytes4, Bytes4],
        op::FOOTER => &[Fixed(20)],
        op::SCHEMA => &[Fixed(2), Bytes4, Bytes4, Bytes4],
        op::CHANNEL => &[Fixed(4), Bytes4, Bytes4, StringMap],
        op::MESSAGE => &[Fixed(22), Rest],
        op::CHUNK => &[Fixed(28), Bytes4, Bytes8],
        op::MESSAGE_INDEX => &[Fixed(2), FixedArray(16)],
        op::CHUNK_INDEX => &[Fixed(32), FixedArray(10), Fixed(8), Bytes4, Fixed(16)],
        op::ATTACHMENT => &[Fixed(16), Bytes4, Bytes4, Bytes8, Fixed(4)],
        op::ATTACHMENT_INDEX => &[Fixed(40), Bytes4, Bytes4],
        op::STATISTICS => &[Fixed(42), FixedArray(10)],
        op::METADATA => &[Bytes4, StringMap],
        op::METADATA_INDEX => &[Fixed(16), Bytes4],
        op::SUMMARY_OFFSET => &[Fixed(17)],
        op::DATA_END => &[Fixed(4)],
        _ => return None,
    })
}

fn u32_at(body: &[u8], at: usize) -> u64 {
    u64::from(u32::from_le_bytes(
        body[at..at + 4].try_into().expect("4 bytes"),
    ))
}

/// Checks that every length in `body` (a record of `opcode`) stays inside it; the error names
/// the field (by its position) and the lengths.
pub fn check_lengths(opcode: u8, body: &[u8]) -> Result<(), String> {
    let Some(fields) = layout(opcode) else {
        return Ok(()); // private or unknown records: the mcap crate keeps their bytes as they are
    };
    let mut at = 0usize;
    let left = |at: usize| body.len().saturating_sub(at) as u64;
    let take = |at: &mut usize, n: u64, what: &str, k: usize| -> Result<(), String> {
        if n > left(*at) {
            return Err(format!(
                "field {k} ({what}) needs {n} bytes at record byte {at} but the record has {} left",
                left(*at)
            ));
        }
        *at += n as usize;
        Ok(())
    };
    for (k, f) in fields.iter().enumerate() {
        match *f {
            Fixed(n) => take(&mut at, n as u64, "fixed fields", k)?,
            Bytes4 | StringMap | FixedArray(_) => {
                take(&mut at, 4, "length prefix", k)?;
                let n = u32_at(body, at - 4);
                let start = at;
                take(&mut at, n, "length-prefixed bytes", k)?;
                match *f {
                    FixedArray(size) if n % size as u64 != 0 => {
                        return Err(format!(
                            "field {k}: an array of {size}-byte entries cannot be {n} bytes long"
                        ))
                    }
                    StringMap => check_string_map(&body[start..at], k)?,
                    _ => {}
                }
            }
            Bytes8 => {
                take(&mut at, 8, "length prefix", k)?;
                let n = u64::from_le_bytes(body[at - 8..at].try_into().expect("8 bytes"));
                take(&mut at, n, "length-prefixed bytes", k)?;
            }
            Rest => at = body.len(),
        }
    }
    Ok(())
}

/// The (str, str) entries of a map fill its span exactly.
fn check_string_map(span: &[u8], k: usize) -> Result<(), String> {
    let mut at = 0usize;
    while at < span.len() {
        for _ in 0..2 {
            if span.len() - at < 4 {
                return Err(format!(
                    "field {k}: a map entry's length prefix runs past the map"
                ));
            }
            let n = u32_at(span, at) as usize;
            at += 4;
            if n > span.len() - at {
                return Err(format!(
                    "field {k}: a map string of {n} bytes at map byte {at} runs past the map ({} bytes)",
                    span.len()
                ));
            }
            at += n;
        }
    }
    Ok(())
}

/// Why a record did not parse.
#[derive(Debug)]
pub enum RecordError {
    /// A length runs past the record (see [`check_lengths`]).
    Layout(String),
    /// The mcap crate's parser refused it.
    Mcap(mcap::McapError),
}

impl std::fmt::Display for RecordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RecordError::Layout(s) => f.write_str(s),
            RecordError::Mcap(e) => write!(f, "{e}"),
        }
    }
}

/// [`mcap::parse_record`] after [`check_lengths`]: the one way this crate parses a record.
pub fn parse_record(opcode: u8, body: &[u8]) -> Result<Record<'_>, RecordError> {
    check_lengths(opcode, body).map_err(RecordError::Layout)?;
    mcap::parse_record(opcode, body).map_err(RecordError::Mcap)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn string(s: &str) -> Vec<u8> {
        let mut v = (s.len() as u32).to_le_bytes().to_vec();
        v.extend_from_slice(s.as_bytes());
        v
    }

    fn chunk(compression: &[u8]) -> Vec<u8> {
        let mut b = vec![0u8; 28];
        b.extend_from_slice(compression);
        b.extend_from_slice(&0u64.to_le_bytes());
        b
    }

    #[test]
    fn a_chunk_whose_compression_length_runs_past_the_record_is_refused_without_allocating() {
        assert!(parse_record(op::CHUNK, &chunk(&string("zstd"))).is_ok());
        let mut claim = 1_454_740_289u32.to_le_bytes().to_vec();
        claim.extend_from_slice(b"zstd");
        let e = parse_record(op::CHUNK, &chunk(&claim))
            .unwrap_err()
            .to_string();
        assert!(e.contains("1454740289") && e.contains("field 1"), "{e}");
    }

    #[test]
    fn channel_metadata_maps_are_checked_entry_by_entry() {
        let mut ok = vec![1, 0, 1, 0];
        ok.extend(string("/t"));
        ok.extend(string("cdr"));
        let entries = [string("k"), string("v")].concat();
        ok.extend((entries.len() as u32).to_le_bytes());
        ok.extend(&entries);
        assert!(parse_record(op::CHANNEL, &ok).is_ok());
        let mut bad = ok.clone();
        let n = bad.len();
        // the value's length (the map's last string) claims more than the map holds
        bad[n - 5] = 200;
        let e = check_lengths(op::CHANNEL, &bad).unwrap_err();
        assert!(e.contains("runs past the map"), "{e}");
        assert!(check_lengths(op::CHANNEL, &ok[..ok.len() - 1]).is_err());
    }

    #[test]
    fn fixed_size_records_and_messages_pass_when_whole() {
        assert!(check_lengths(op::FOOTER, &[0u8; 20]).is_ok());
        assert!(check_lengths(op::FOOTER, &[0u8; 19]).is_err());
        assert!(check_lengths(op::MESSAGE, &[0u8; 22]).is_ok());
        assert!(check_lengths(op::MESSAGE, &[0u8; 30]).is_ok());
        assert!(check_lengths(0x80, &[1, 2, 3]).is_ok());
    }
}
