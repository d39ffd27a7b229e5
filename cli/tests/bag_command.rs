//! `metrocell bag` on a `metrocell sim` recording (issue 32): filter refuses a selection that
//! holds nothing, listing the topics; info of a missing path is an error; a damaged bag's readers
//! say "run `metrocell bag recover DIR`", after which it reads again; and every `bag export`
//! format comes back through `bag import` without a mapping — the same messages, byte for byte,
//! at the same log and publish times, on the same topics with the same types and QoS.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::metrocell;
use metrocell_bag::{BagReader, MessageFilter};

fn cell(name: &str) -> String {
    format!(
        "{}/../launch-configs/cells/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// A 10-minute recording of the quick demo cell in `d/bag`.
fn quick_bag(d: &Path) -> PathBuf {
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            &cell("quick_demo.yaml"),
            "--duration",
            "10min",
            "--no-camera-frames",
            "--quiet",
            "-o",
            "bag",
        ],
        d,
    );
    assert_eq!(code, 0, "{out}{err}");
    d.join("bag")
}

/// Per topic: type, offered QoS, and every message as (log time, publish time, bytes).
type Contents = BTreeMap<String, (String, String, Vec<(u64, u64, Vec<u8>)>)>;

fn contents(bag: &Path) -> Contents {
    let r = BagReader::open(bag).unwrap_or_else(|e| panic!("{}: {e}", bag.display()));
    let mut out: Contents = r
        .topics()
        .iter()
        .map(|t| {
            (
                t.name.clone(),
                (
                    t.type_name.clone(),
                    t.offered_qos_profiles.clone(),
                    Vec::new(),
                ),
            )
        })
        .collect();
    for m in r.read_all(&MessageFilter::default()).unwrap() {
        out.get_mut(&m.topic)
            .unwrap()
            .2
            .push((m.log_time, m.publish_time, m.data));
    }
    out
}

#[test]
fn every_export_format_comes_back_through_import() {
    let d = common::scratch("bag", "roundtrip");
    let bag = quick_bag(&d);
    let original = contents(&bag);
    assert!(
        original
            .get("/tracker/measurements")
            .is_some_and(|t| t.2.len() > 1000),
        "the recording holds the tracker's readings"
    );
    for format in ["csv", "parquet"] {
        let export = format!("export_{format}");
        let (code, out, err) = metrocell(
            &["bag", "export", "bag", "--format", format, "-o", &export],
            &d,
        );
        assert_eq!(code, 0, "{out}{err}");
        assert!(
            d.join(&export).join("export.yaml").exists(),
            "the manifest beside the {format} files"
        );
        let again = format!("again_{format}");
        let (code, out, err) = metrocell(&["bag", "import", &export, "-o", &again], &d);
        assert_eq!(code, 0, "{format}: {out}{err}");
        let rebuilt = contents(&d.join(&again));
        assert_eq!(
            rebuilt.keys().collect::<Vec<_>>(),
            original.keys().collect::<Vec<_>>(),
            "{format}: the same topics"
        );
        for (topic, (ty, qos, messages)) in &original {
            let (ty2, qos2, messages2) = &rebuilt[topic];
            assert_eq!((ty2, qos2), (ty, qos), "{format}: {topic}'s type and QoS");
            assert_eq!(
                messages2.len(),
                messages.len(),
                "{format}: {topic}'s message count"
            );
            assert!(
                messages2 == messages,
                "{format}: {topic}: a message differs in bytes, log time or publish time"
            );
        }
    }
    // the empty topic (no camera frames) exports as its header, and comes back as an empty topic
    let empty = std::fs::read_to_string(d.join("export_csv/camera.image_raw.csv")).unwrap();
    assert!(empty.starts_with("log_time_ns,publish_time_ns,header.stamp.sec,header.stamp.nanosec,header.frame_id,height,width,encoding,"), "{empty}");
    assert_eq!(empty.lines().count(), 1, "{empty}");
    // one exported CSV copied away from its manifest: the topic from its name, the type from its columns
    std::fs::create_dir_all(d.join("alone")).unwrap();
    std::fs::copy(
        d.join("export_csv/tracker.measurements.csv"),
        d.join("alone/tracker.measurements.csv"),
    )
    .unwrap();
    let (code, out, err) = metrocell(
        &[
            "bag",
            "import",
            "alone/tracker.measurements.csv",
            "-o",
            "alone_bag",
        ],
        &d,
    );
    assert_eq!(code, 0, "{out}{err}");
    let alone = contents(&d.join("alone_bag"));
    let (ty, _, messages) = &alone["/tracker/measurements"];
    assert_eq!(ty, "metrocell_msgs/msg/TrackerMeasurement");
    assert!(
        messages == &original["/tracker/measurements"].2,
        "the same readings at the same times"
    );
}

#[test]
fn filter_refuses_a_selection_that_holds_nothing() {
    let d = common::scratch("bag", "filter");
    quick_bag(&d);
    // the README's example once read '^/temperature/': a regex matches the whole name
    let (code, out, err) = metrocell(
        &["bag", "filter", "bag", "none", "--regex", "^/temperature/"],
        &d,
    );
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("no topic of bag matches regex '^/temperature/'")
            && err.contains("/temperature/x_left")
            && err.contains("'/temperature/.*'"),
        "{err}"
    );
    assert!(!d.join("none").exists(), "no empty bag written");
    let (code, _, err) = metrocell(&["bag", "filter", "bag", "none", "--topics", "/nope"], &d);
    assert!(
        code == 2
            && err.contains("/nope: not in bag (topics: ")
            && err.contains("/tracker/measurements"),
        "{err}"
    );
    let (code, _, err) = metrocell(
        &[
            "bag",
            "filter",
            "bag",
            "none",
            "--regex",
            "/temperature/.*",
            "--start",
            "5000",
        ],
        &d,
    );
    assert!(
        code == 2
            && err.contains(
                "no message of regex '/temperature/.*' lies in the window from 5000.000 s"
            ),
        "{err}"
    );
    assert!(!d.join("none").exists());
    let (code, out, err) = metrocell(
        &[
            "bag",
            "filter",
            "bag",
            "temps",
            "--regex",
            "/temperature/.*",
            "--start",
            "10",
            "--end",
            "70",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("wrote 120 messages"),
        "two sensors at 1 Hz for 60 s: {out}"
    );
}

#[test]
fn a_missing_or_damaged_bag_says_what_to_do() {
    let d = common::scratch("bag", "damaged");
    quick_bag(&d);
    let (code, out, err) = metrocell(&["bag", "info", "no_such_bag"], &d);
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("no bag at no_such_bag") && !out.contains("Problem"),
        "{out}{err}"
    );
    // cut the file as a crash would
    let file = std::fs::read_dir(d.join("bag"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "mcap"))
        .unwrap();
    let len = std::fs::metadata(&file).unwrap().len();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&file)
        .unwrap()
        .set_len(len * 2 / 3)
        .unwrap();
    let next_step = "run `metrocell bag recover bag`";
    let (code, out, err) = metrocell(&["bag", "info", "bag"], &d);
    assert_eq!(code, 1, "a damaged bag: {out}{err}");
    assert!(out.contains("Problem:") && out.contains(next_step), "{out}");
    for args in [
        &["diagnose", "--model", &cell("quick_demo.yaml"), "bag"][..],
        &[
            "calibrate",
            "--model",
            &cell("quick_demo.yaml"),
            "bag",
            "-o",
            "y.yaml",
        ],
        &["bag", "export", "bag", "-o", "csv"],
    ] {
        let (code, _, err) = metrocell(args, &d);
        assert_ne!(code, 0, "{args:?}");
        assert!(
            err.contains("truncated") && err.contains(next_step),
            "{args:?}: {err}"
        );
    }
    let (code, out, err) = metrocell(&["bag", "recover", "bag"], &d);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            &cell("quick_demo.yaml"),
            "bag",
            "-o",
            "y.yaml",
        ],
        &d,
    );
    assert_eq!(code, 0, "the recovered bag reads: {out}{err}");
}
