//! Interop with real peers: bags written by BagWriter are read by Python `rosbags` and by
//! `mcap` + `mcap-ros2-support`; a bag written by `rosbags` is read by BagReader.

mod support;

use std::path::Path;

use metrocell_bag::{
    qos_profiles_yaml, BagReader, BagWriter, ChunkCompression, MessageFilter, QosProfile,
    SplitPolicy, WriterOptions,
};
use support::*;

const N: u64 = 600;
const T0: u64 = 1_700_000_000_000_000_000;

/// Write N temperatures and N strings, interleaved by log time, small chunks, split by size.
fn write_bag(dir: &Path, compression: ChunkCompression) -> metrocell_bag::BagMetadata {
    let opts = WriterOptions {
        compression,
        chunk_size: 4096,
        split: SplitPolicy {
            max_file_bytes: Some(24 * 1024),
            max_file_duration: None,
        },
        ..Default::default()
    };
    let mut w = BagWriter::create(dir, opts).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/temperature",
        "sensor_msgs/msg/Temperature",
        TEMPERATURE_DEF,
        &qos,
    )
    .unwrap();
    w.add_topic("/note", "std_msgs/msg/String", STRING_DEF, &qos)
        .unwrap();
    for i in 0..N {
        let t = T0 + i * 1_000_000;
        w.write("/temperature", t, t - 10, &Temperature::nth(i).encode())
            .unwrap();
        w.write("/note", t + 500, t, &encode_string(&format!("note {i}")))
            .unwrap();
    }
    w.finish().unwrap()
}

fn check_python_output(v: &serde_json::Value) {
    assert_eq!(
        v["topics"]["/temperature"]["count"].as_u64(),
        Some(N),
        "{}",
        v["topics"]
    );
    assert_eq!(v["topics"]["/note"]["count"].as_u64(), Some(N));
    assert_eq!(
        v["topics"]["/temperature"]["type"].as_str(),
        Some("sensor_msgs/msg/Temperature")
    );
    let msgs = v["messages"].as_array().unwrap();
    assert_eq!(msgs.len() as u64, 2 * N);
    let (mut it, mut in_) = (0u64, 0u64);
    for m in msgs {
        match m["topic"].as_str().unwrap() {
            "/temperature" => {
                assert_eq!(m["log_time"].as_u64(), Some(T0 + it * 1_000_000));
                Temperature::nth(it).assert_json(&m["msg"]);
                it += 1;
            }
            "/note" => {
                assert_eq!(m["msg"]["data"].as_str().unwrap(), format!("note {in_}"));
                in_ += 1;
            }
            other => panic!("unexpected topic {other}"),
        }
    }
    assert_eq!((it, in_), (N, N));
}

#[test]
fn bagwriter_bags_read_by_rosbags_and_mcap_ros2() {
    for (name, c) in [
        ("zstd", ChunkCompression::Zstd),
        ("lz4", ChunkCompression::Lz4),
        ("none", ChunkCompression::None),
    ] {
        let dir = scratch(&format!("interop-{name}")).join("rec");
        let meta = write_bag(&dir, c);
        assert!(
            meta.relative_file_paths.len() >= 2,
            "split by size made {:?}",
            meta.relative_file_paths
        );
        assert_eq!(meta.message_count, 2 * N);
        assert_eq!(meta.relative_file_paths[0], "rec_0.mcap");

        // rosbags (directory, through metadata.yaml), types from the bag's definitions.
        check_python_output(&run_py("read_with_rosbags.py", &[&dir]));

        // mcap + mcap-ros2-support, file by file.
        let files: Vec<_> = meta
            .relative_file_paths
            .iter()
            .map(|p| dir.join(p))
            .collect();
        let refs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
        let v = run_py("read_with_mcap.py", &refs);
        assert!(v["profiles"]
            .as_array()
            .unwrap()
            .iter()
            .all(|p| p == "ros2"));
        check_python_output(&v);

        // Our reader: same bytes back, in log-time order.
        let r = BagReader::open(&dir).unwrap();
        let all = r.read_all(&MessageFilter::default()).unwrap();
        assert_eq!(all.len() as u64, 2 * N);
        assert!(all.windows(2).all(|w| w[0].log_time <= w[1].log_time));
        let temps: Vec<_> = all.iter().filter(|m| m.topic == "/temperature").collect();
        for (i, m) in temps.iter().enumerate() {
            assert_eq!(m.data, Temperature::nth(i as u64).encode());
            assert_eq!(m.publish_time, m.log_time - 10);
        }
        let t = r.topic("/temperature").unwrap();
        assert_eq!(t.definition, TEMPERATURE_DEF);
        assert_eq!(t.message_count, N);
        assert!(t.offered_qos_profiles.contains("depth: 10"));
    }
}

#[test]
fn rosbags_written_bag_reads_with_equal_fields() {
    let dir = scratch("from-rosbags").join("pybag");
    let out = std::process::Command::new(python())
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/write_with_rosbags.py"))
        .arg(&dir)
        .arg("250")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let r = BagReader::open(&dir).unwrap();
    assert_eq!(r.metadata().unwrap().version, 9);
    let t = r.topic("/temperature").unwrap();
    assert_eq!(t.type_name, "sensor_msgs/msg/Temperature");
    assert_eq!(t.message_count, 250);
    assert!(t.definition.contains("MSG: builtin_interfaces/Time"));
    assert_eq!(r.topic("/note").unwrap().message_count, 250);

    let temps = r
        .read_all(&MessageFilter {
            topics: Some(vec!["/temperature".into()]),
            ..Default::default()
        })
        .unwrap();
    assert_eq!(temps.len(), 250);
    for (i, m) in temps.iter().enumerate() {
        let expect = Temperature::nth(i as u64);
        // Same field values, and byte-identical CDR to our own encoder.
        assert_eq!(Temperature::decode(&m.data), expect);
        assert_eq!(m.data, expect.encode());
        assert_eq!(m.log_time, 1_000_000_000_000_000_000 + i as u64 * 1_000_000);
    }
    // Time window [t(10), t(20)) over both topics: 10 temperatures + 10 notes.
    let w = r
        .read_all(&MessageFilter {
            topics: None,
            start_ns: Some(1_000_000_000_000_000_000 + 10_000_000),
            end_ns: Some(1_000_000_000_000_000_000 + 20_000_000),
        })
        .unwrap();
    assert_eq!(w.len(), 20);
    assert_eq!(decode_string(&w[1].data), "note 10");
}
