//! BagWriter behaviour: splitting, argument checks, and stopping cleanly on a full disk.

mod support;

use std::time::Duration;

use metrocell_bag::{
    info, qos_profiles_yaml, BagError, BagReader, BagWriter, MessageFilter, QosProfile,
    SplitPolicy, WriterOptions,
};
use support::*;

const T0: u64 = 1_700_000_000_000_000_000;

fn qos() -> String {
    qos_profiles_yaml(&[QosProfile::default_publisher()])
}

#[test]
fn split_by_duration_lists_every_file_in_metadata() {
    let dir = scratch("split-dur").join("cell");
    let opts = WriterOptions {
        split: SplitPolicy {
            max_file_bytes: None,
            max_file_duration: Some(Duration::from_secs(1)),
        },
        ..Default::default()
    };
    let mut w = BagWriter::create(&dir, opts).unwrap();
    w.add_topic(
        "/temperature",
        "sensor_msgs/msg/Temperature",
        TEMPERATURE_DEF,
        &qos(),
    )
    .unwrap();
    // 35 messages at 10 Hz = 3.4 s of log time -> files of [0,1) s, [1,2) s, [2,3) s, [3,3.4] s.
    for i in 0..35u64 {
        let t = T0 + i * 100_000_000;
        w.write("/temperature", t, t, &Temperature::nth(i).encode())
            .unwrap();
    }
    let m = w.finish().unwrap();
    assert_eq!(
        m.relative_file_paths,
        vec!["cell_0.mcap", "cell_1.mcap", "cell_2.mcap", "cell_3.mcap"]
    );
    let counts: Vec<u64> = m.files.iter().map(|f| f.message_count).collect();
    assert_eq!(counts, vec![10, 10, 10, 5]);
    assert_eq!(
        m.files[1].starting_time.nanoseconds_since_epoch,
        T0 + 1_000_000_000
    );
    assert_eq!(m.duration.nanoseconds, 3_400_000_000);

    // Each file carries rosbag2's `rosbag2` Metadata record: the bare bagfile-information
    // mapping (no wrapper key), as rosbag2's MCAP plugin reads it back.
    let bytes = std::fs::read(dir.join("cell_1.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let idx = summary
        .metadata_indexes
        .iter()
        .find(|m| m.name == "rosbag2")
        .expect("rosbag2 metadata");
    let md = mcap::read::metadata(&bytes, idx).unwrap();
    let inner: serde_yaml::Value =
        serde_yaml::from_str(&md.metadata["serialized_metadata"]).unwrap();
    assert_eq!(inner["version"].as_u64(), Some(8));
    assert_eq!(inner["storage_identifier"].as_str(), Some("mcap"));
    assert!(inner.get("rosbag2_bagfile_information").is_none());

    let r = BagReader::open(&dir).unwrap();
    let all = r.read_all(&MessageFilter::default()).unwrap();
    assert_eq!(all.len(), 35);
    assert!(all
        .iter()
        .enumerate()
        .all(|(i, m)| m.data == Temperature::nth(i as u64).encode()));

    let inf = info(&dir).unwrap();
    assert_eq!(inf.files.len(), 4);
    assert_eq!(inf.message_count, 35);
    assert_eq!(inf.duration_ns, 3_400_000_000);
    // 34 intervals over 3.4 s = 10 Hz.
    assert!((inf.topics[0].rate_hz.unwrap() - 10.0).abs() < 1e-9);
    let text = inf.to_string();
    assert!(
        text.contains("cell_3.mcap") && text.contains("Count: 35") && text.contains("10.000 Hz"),
        "{text}"
    );
}

#[test]
fn out_of_order_log_times_are_replayed_in_order() {
    let dir = scratch("order").join("o");
    let opts = WriterOptions {
        chunk_size: 256,
        ..Default::default()
    };
    let mut w = BagWriter::create(&dir, opts).unwrap();
    w.add_topic(
        "/temperature",
        "sensor_msgs/msg/Temperature",
        TEMPERATURE_DEF,
        &qos(),
    )
    .unwrap();
    // Write indices in a scrambled but deterministic order across many chunks.
    let order: Vec<u64> = (0..200u64).map(|i| (i * 73) % 200).collect();
    for &i in &order {
        w.write(
            "/temperature",
            T0 + i,
            T0 + i,
            &Temperature::nth(i).encode(),
        )
        .unwrap();
    }
    w.finish().unwrap();
    let r = BagReader::open(&dir).unwrap();
    let all = r.read_all(&MessageFilter::default()).unwrap();
    let times: Vec<u64> = all.iter().map(|m| m.log_time - T0).collect();
    assert_eq!(times, (0..200).collect::<Vec<_>>());
}

#[test]
fn bad_arguments_are_rejected_with_reasons() {
    let dir = scratch("args").join("a");
    let short = WriterOptions {
        flush_interval: Duration::from_millis(50),
        ..Default::default()
    };
    assert!(matches!(
        BagWriter::create(&dir, short),
        Err(BagError::InvalidArgument(_))
    ));
    let mut w = BagWriter::create(&dir, WriterOptions::default()).unwrap();
    assert!(w.add_topic("no_slash", "a/msg/B", "int32 x\n", "").is_err());
    assert!(w
        .add_topic("/t", "Temperature", TEMPERATURE_DEF, "")
        .is_err());
    let e = w
        .add_topic("/t", "p/msg/T", "float64[ x\n", "")
        .unwrap_err();
    assert!(e.to_string().contains("line 1"), "{e}");
    assert!(w
        .add_topic("/t", "p/msg/T", "float64 x\n", "not: [a, sequence")
        .is_err());
    w.add_topic("/t", "p/msg/T", "float64 x\n", "").unwrap();
    let e = w.write("/t", 1, 1, &[1, 2, 3, 4, 5]).unwrap_err();
    assert!(e.to_string().contains("encapsulation"), "{e}");
    assert!(w.write("/nope", 1, 1, &[0, 1, 0, 0]).is_err());
    // A second bag in the same directory is refused.
    assert!(BagWriter::create(&dir, WriterOptions::default()).is_err());
}

/// The sink fails with ENOSPC after a byte budget: the writer reports the file, keeps what
/// was flushed, and leaves a bag that both our strict reader and rosbags read.
#[test]
fn full_disk_stops_with_named_error_and_a_readable_bag() {
    let dir = scratch("enospc").join("full");
    let opts = WriterOptions {
        chunk_size: 2048,
        fail_after_bytes: Some(40_000),
        ..Default::default()
    };
    let mut w = BagWriter::create(&dir, opts).unwrap();
    w.add_topic(
        "/temperature",
        "sensor_msgs/msg/Temperature",
        TEMPERATURE_DEF,
        &qos(),
    )
    .unwrap();
    let mut written = 0u64;
    let err = loop {
        let t = T0 + written * 1_000_000;
        match w.write("/temperature", t, t, &Temperature::nth(written).encode()) {
            Ok(()) => written += 1,
            Err(e) => break e,
        }
        if written % 50 == 0 {
            if let Err(e) = w.flush() {
                break e;
            }
        }
        assert!(written < 100_000, "the byte budget never ran out");
    };
    let BagError::WriteFailed {
        path,
        source,
        kept_messages,
        lost_messages,
    } = &err
    else {
        panic!("expected WriteFailed, got {err:?}");
    };
    assert_eq!(path, &dir.join("full_0.mcap"));
    assert_eq!(source.raw_os_error(), Some(28), "ENOSPC");
    assert!(err.to_string().contains("full_0.mcap"), "{err}");
    assert!(
        *kept_messages > 0 && *kept_messages % 50 == 0,
        "kept {kept_messages}"
    );
    assert_eq!(kept_messages + lost_messages, written);
    // Later calls say the writer is closed.
    assert!(matches!(
        w.write("/temperature", T0, T0, &Temperature::nth(0).encode()),
        Err(BagError::Closed { .. })
    ));
    drop(w);

    let r = BagReader::open(&dir).expect("sealed bag reads strictly");
    let msgs = r.read_all(&MessageFilter::default()).unwrap();
    assert_eq!(msgs.len() as u64, *kept_messages);
    assert!(msgs
        .iter()
        .enumerate()
        .all(|(i, m)| m.data == Temperature::nth(i as u64).encode()));
    assert_eq!(r.metadata().unwrap().message_count, *kept_messages);
    let v = run_py("read_with_rosbags.py", &[&dir]);
    assert_eq!(
        v["messages"].as_array().unwrap().len() as u64,
        *kept_messages
    );
}

/// A disk that is full from the first byte: `create` fails cleanly, naming the file, and
/// leaves no non-MCAP file behind (nothing panics in Drop).
#[test]
fn full_disk_at_create_is_an_error_not_a_panic() {
    let dir = scratch("enospc-create").join("empty");
    let opts = WriterOptions {
        fail_after_bytes: Some(10),
        ..Default::default()
    };
    let err = BagWriter::create(&dir, opts)
        .err()
        .expect("create must fail");
    assert!(err.to_string().contains("empty_0.mcap"), "{err}");
    assert!(!dir.join("empty_0.mcap").exists());
}
