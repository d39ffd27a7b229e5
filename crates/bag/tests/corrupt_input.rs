//! Corrupt input: errors name file, byte offset and record kind; tolerant mode still reads
//! everything intact. Offsets are cross-checked with the `mcap` crate's own index.

mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_bag::{
    info, qos_profiles_yaml, BagError, BagReader, BagWriter, ChunkCompression, MessageFilter,
    QosProfile, ReadMode, WriterOptions,
};
use support::*;

const T0: u64 = 1_700_000_000_000_000_000;
const N: u64 = 500;

/// A finished single-file bag of N temperatures in small uncompressed chunks.
fn good_file(name: &str) -> (PathBuf, Vec<u8>) {
    let dir = scratch(name).join("b");
    let opts = WriterOptions {
        compression: ChunkCompression::None,
        chunk_size: 1024,
        ..Default::default()
    };
    let mut w = BagWriter::create(&dir, opts).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/temperature",
        "sensor_msgs/msg/Temperature",
        TEMPERATURE_DEF,
        &qos,
    )
    .unwrap();
    for i in 0..N {
        w.write(
            "/temperature",
            T0 + i,
            T0 + i,
            &Temperature::nth(i).encode(),
        )
        .unwrap();
    }
    w.finish().unwrap();
    let f = dir.join("b_0.mcap");
    let bytes = std::fs::read(&f).unwrap();
    (f, bytes)
}

fn corrupt_parts(e: &BagError) -> (&Path, u64, &'static str, &str) {
    // a strict reader wraps the damage with the next step (`metrocell bag recover`)
    assert!(
        matches!(e, BagError::Damaged { .. })
            && e.to_string().contains("run `metrocell bag recover "),
        "{e}"
    );
    match e.damage() {
        BagError::Corrupt {
            path,
            offset,
            record,
            reason,
        } => (path.as_path(), *offset, record, reason.as_str()),
        other => panic!("expected Corrupt, got {other:?}"),
    }
}

/// (chunk start, chunk length, messages) of every message-bearing chunk, from the mcap crate.
fn chunks(bytes: &[u8]) -> Vec<(u64, u64, u64)> {
    let s = mcap::Summary::read(bytes).unwrap().unwrap();
    s.chunk_indexes
        .iter()
        .map(|c| {
            (
                c.chunk_start_offset,
                c.chunk_length,
                s.stream_chunk(bytes, c).unwrap().count() as u64,
            )
        })
        .filter(|c| c.2 > 0)
        .collect()
}

#[test]
fn garbage_and_wrong_magic_name_offset_zero() {
    let dir = scratch("garbage");
    let g = dir.join("garbage.mcap");
    std::fs::write(&g, b"this is not an mcap file at all, just text\n").unwrap();
    let e = BagReader::open(&g).err().unwrap();
    let (p, off, kind, reason) = corrupt_parts(&e);
    assert_eq!((p, off, kind), (g.as_path(), 0, "magic"));
    assert!(reason.contains("not an MCAP"), "{reason}");
    assert!(
        e.to_string().contains("garbage.mcap") && e.to_string().contains("offset 0"),
        "{e}"
    );

    let (_, mut bytes) = good_file("wrong-magic");
    bytes[3] = b'X';
    let w = dir.join("wrong_magic.mcap");
    std::fs::write(&w, &bytes).unwrap();
    let e = BagReader::open(&w).err().unwrap();
    assert_eq!(corrupt_parts(&e).1, 0);
    assert_eq!(corrupt_parts(&e).2, "magic");
}

#[test]
fn bad_chunk_crc_is_named_and_skipped_in_tolerant_mode() {
    let (f, mut bytes) = good_file("crc");
    let cs = chunks(&bytes);
    assert!(cs.len() > 10);
    let (start, len, lost) = cs[cs.len() / 2];
    // Flip a byte in the last quarter of the chunk's (uncompressed) payload.
    let victim = (start + len - len / 4) as usize;
    bytes[victim] ^= 0x55;
    std::fs::write(&f, &bytes).unwrap();

    let e = BagReader::open(&f).err().unwrap();
    let (p, off, kind, reason) = corrupt_parts(&e);
    assert_eq!((p, off, kind), (f.as_path(), start, "Chunk"));
    assert!(reason.contains("CRC mismatch"), "{reason}");

    let r = BagReader::open_with(&f, ReadMode::Tolerant).unwrap();
    assert_eq!(r.problems().len(), 1);
    let msgs = r.read_all(&MessageFilter::default()).unwrap();
    assert_eq!(msgs.len() as u64, N - lost);
    for m in &msgs {
        let i = m.log_time - T0;
        assert_eq!(
            m.data,
            Temperature::nth(i).encode(),
            "no altered message survives"
        );
    }
    let inf = info(&f).unwrap();
    assert_eq!(inf.message_count, N - lost);
    assert_eq!(inf.problems.len(), 1);
    assert!(inf.to_string().contains("CRC mismatch"));
}

#[test]
fn truncated_file_names_the_cut_chunk_and_keeps_the_rest() {
    let (f, bytes) = good_file("trunc");
    let cs = chunks(&bytes);
    let k = cs.len() * 2 / 3;
    let (start, len, _) = cs[k];
    let cut = (start + len / 2) as usize;
    std::fs::write(&f, &bytes[..cut]).unwrap();

    let e = BagReader::open(&f).err().unwrap();
    let (p, off, kind, reason) = corrupt_parts(&e);
    assert_eq!((p, off, kind), (f.as_path(), start, "Chunk"));
    assert!(reason.contains("truncated"), "{reason}");

    let r = BagReader::open_with(&f, ReadMode::Tolerant).unwrap();
    let before: u64 = cs[..k].iter().map(|c| c.2).sum();
    assert_eq!(
        r.read_all(&MessageFilter::default()).unwrap().len() as u64,
        before
    );
}

#[test]
fn schema_that_does_not_parse_is_named_with_its_offset() {
    let dir = scratch("badschema");
    let f = dir.join("bad_schema.mcap");
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .library("test")
        .use_chunks(false)
        .create(std::io::BufWriter::new(std::fs::File::create(&f).unwrap()))
        .unwrap();
    let sid = w
        .add_schema("p/msg/Bad", "ros2msg", b"float64 x\nfloat64[ y\n")
        .unwrap();
    let cid = w.add_channel(sid, "/bad", "cdr", &BTreeMap::new()).unwrap();
    let h = mcap::records::MessageHeader {
        channel_id: cid,
        sequence: 1,
        log_time: 5,
        publish_time: 5,
    };
    w.write_to_known_channel(&h, &[0, 1, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8])
        .unwrap();
    w.finish().unwrap();
    drop(w);
    // Magic (8) + Header record (1 + 8 + (4 + 4) + (4 + 4)) precede the Schema record.
    let schema_offset = 8 + 9 + 8 + 4 + 4;
    let e = BagReader::open(&f).err().unwrap();
    let (_, off, kind, reason) = corrupt_parts(&e);
    assert_eq!((off, kind), (schema_offset, "Schema"));
    assert!(
        reason.contains("line 2") && reason.contains("p/msg/Bad"),
        "{reason}"
    );
    // Tolerant: the message bytes are still readable.
    let r = BagReader::open_with(&f, ReadMode::Tolerant).unwrap();
    assert_eq!(r.read_all(&MessageFilter::default()).unwrap().len(), 1);
}

#[test]
fn invalid_metadata_yaml_names_the_file() {
    let (f, _) = good_file("badmeta");
    let dir = f.parent().unwrap();
    std::fs::write(
        dir.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: [oops\n",
    )
    .unwrap();
    let e = BagReader::open(dir).err().unwrap();
    assert!(matches!(e, BagError::Metadata { .. }), "{e:?}");
    assert!(e.to_string().contains("metadata.yaml"), "{e}");
}

/// A chunk whose length field is destroyed breaks record framing; strict reading names it,
/// tolerant reading and recovery resynchronise on the next verified chunk and keep the rest.
#[test]
fn broken_framing_mid_file_resynchronises_on_the_next_chunk() {
    let (f, mut bytes) = good_file("framing");
    let cs = chunks(&bytes);
    let (start, _, lost) = cs[cs.len() / 2];
    bytes[start as usize + 1..start as usize + 9].copy_from_slice(&u64::MAX.to_le_bytes());
    std::fs::write(&f, &bytes).unwrap();

    let e = BagReader::open(&f).err().unwrap();
    let (_, off, kind, reason) = corrupt_parts(&e);
    assert_eq!((off, kind), (start, "Chunk"), "{reason}");

    let r = BagReader::open_with(&f, ReadMode::Tolerant).unwrap();
    let msgs = r.read_all(&MessageFilter::default()).unwrap();
    assert_eq!(msgs.len() as u64, N - lost);
    assert!(msgs
        .iter()
        .all(|m| m.data == Temperature::nth(m.log_time - T0).encode()));

    let rep = metrocell_bag::recover(&f).unwrap();
    assert_eq!(rep.kept_messages(), N - lost);
    assert!(rep.to_string().contains("resumed"), "{rep}");
    let r = BagReader::open(&f).unwrap();
    assert_eq!(r.message_count(), N - lost);
}
