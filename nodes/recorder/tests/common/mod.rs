#![allow(dead_code)]
//! Helpers shared by the recorder's integration tests.

use std::path::{Path, PathBuf};

use metrocell_node::MetrocellNode;
use rustdds::discovery::PublicationBuiltinTopicData;

/// The `metrocell` binary next to this package's binaries (or `METROCELL_CLI`).
pub fn cli() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_CLI") {
        return p.into();
    }
    let p = PathBuf::from(env!("CARGO_BIN_EXE_metrocell-recorder")).with_file_name("metrocell");
    assert!(
        p.exists(),
        "{} missing: run `cargo build -p metrocell-cli` first or set METROCELL_CLI",
        p.display()
    );
    p
}

/// The Python with rosbags: `METROCELL_PYTHON`, else the workspace's `.venv` (made by tests/run).
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return p.into();
    }
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    assert!(
        p.exists(),
        "no Python with rosbags: set METROCELL_PYTHON or run tests/run (which creates .venv)"
    );
    p
}

/// What the discovered writers of ROS topic `topic` announce.
pub fn writers_of(node: &MetrocellNode, topic: &str) -> Vec<PublicationBuiltinTopicData> {
    let dds = metrocell_node::names::dds_topic_name(topic);
    node.context()
        .domain_participant()
        .discovered_writers()
        .into_iter()
        .filter(|w| w.publication_topic_data.topic_name == dds)
        .map(|w| w.publication_topic_data)
        .collect()
}
