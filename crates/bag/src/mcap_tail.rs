//! Hand-built MCAP records that close a data section without a summary: `DataEnd`
//! (data-section CRC 0 = not computed), `Footer` (summary start 0 = no summary section) and the
//! closing magic. Appending these at a record boundary makes a valid MCAP file that readers
//! scan linearly.

/// DataEnd + Footer + magic, 13 + 29 + 8 = 50 bytes.
pub(crate) fn summaryless_tail() -> Vec<u8> {
    let mut v = Vec::with_capacity(50);
    v.push(mcap::records::op::DATA_END);
    v.extend_from_slice(&4u64.to_le_bytes());
    v.extend_from_slice(&0u32.to_le_bytes());
    v.push(mcap::records::op::FOOTER);
    v.extend_from_slice(&20u64.to_le_bytes());
    v.extend_from_slice(&0u64.to_le_bytes()); // summary_start
    v.extend_from_slice(&0u64.to_le_bytes()); // summary_offset_start
    v.extend_from_slice(&0u32.to_le_bytes()); // summary_crc
    v.extend_from_slice(mcap::MAGIC);
    v
}
