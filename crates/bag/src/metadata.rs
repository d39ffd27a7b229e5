//! `metadata.yaml` of a rosbag2 bag directory (`rosbag2_bagfile_information`).
//!
//! Written as version 8 (the layout of rosbag2 Iron/Jazzy: `files`, `custom_data`,
//! `ros_distro`, `type_description_hash`, and `offered_qos_profiles` as a YAML *string*).
//! Read leniently: versions 1..=9, `offered_qos_profiles` as a string or (rosbags v9) a
//! sequence. Times are nanoseconds: `starting_time.nanoseconds_since_epoch` is the earliest
//! message log time and `duration.nanoseconds` is last minus first log time.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{io_err, BagError, Result};

pub const METADATA_FILE: &str = "metadata.yaml";
pub const WRITTEN_VERSION: u32 = 8;

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Nanoseconds {
    pub nanoseconds: u64,
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct NanosecondsSinceEpoch {
    pub nanoseconds_since_epoch: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicMetadata {
    pub name: String,
    #[serde(rename = "type")]
    pub type_name: String,
    pub serialization_format: String,
    /// YAML text; a sequence in rosbags v9 files is re-serialised to text on read.
    #[serde(default, deserialize_with = "string_or_yaml")]
    pub offered_qos_profiles: String,
    #[serde(default)]
    pub type_description_hash: String,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicWithMessageCount {
    pub topic_metadata: TopicMetadata,
    pub message_count: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileInformation {
    pub path: String,
    pub starting_time: NanosecondsSinceEpoch,
    pub duration: Nanoseconds,
    pub message_count: u64,
}

/// The `rosbag2_bagfile_information` mapping.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BagMetadata {
    pub version: u32,
    pub storage_identifier: String,
    pub duration: Nanoseconds,
    pub starting_time: NanosecondsSinceEpoch,
    pub message_count: u64,
    pub topics_with_message_count: Vec<TopicWithMessageCount>,
    #[serde(default)]
    pub compression_format: String,
    #[serde(default)]
    pub compression_mode: String,
    pub relative_file_paths: Vec<String>,
    #[serde(default)]
    pub files: Vec<FileInformation>,
    #[serde(default, deserialize_with = "map_or_null")]
    pub custom_data: std::collections::BTreeMap<String, String>,
    #[serde(default, deserialize_with = "string_or_null")]
    pub ros_distro: String,
}

#[derive(Debug, Serialize, Deserialize)]
struct MetadataDocument {
    rosbag2_bagfile_information: BagMetadata,
}

fn string_or_yaml<'de, D: serde::Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let v = serde_yaml::Value::deserialize(d)?;
    Ok(match v {
        serde_yaml::Value::Null => String::new(),
        serde_yaml::Value::String(s) => s,
        other => serde_yaml::to_string(&other)
            .map_err(serde::de::Error::custom)?
            .trim_end()
            .to_string(),
    })
}

fn string_or_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    Ok(Option::<String>::deserialize(d)?.unwrap_or_default())
}

fn map_or_null<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<std::collections::BTreeMap<String, String>, D::Error> {
    Ok(Option::deserialize(d)?.unwrap_or_default())
}

impl BagMetadata {
    /// An empty version-8 MCAP metadata record.
    pub fn empty() -> Self {
        Self {
            version: WRITTEN_VERSION,
            storage_identifier: "mcap".into(),
            duration: Nanoseconds::default(),
            starting_time: NanosecondsSinceEpoch::default(),
            message_count: 0,
            topics_with_message_count: Vec::new(),
            compression_format: String::new(),
            compression_mode: String::new(),
            relative_file_paths: Vec::new(),
            files: Vec::new(),
            custom_data: Default::default(),
            ros_distro: std::env::var("ROS_DISTRO").unwrap_or_default(),
        }
    }

    pub fn to_yaml(&self) -> String {
        let doc = MetadataDocument {
            rosbag2_bagfile_information: self.clone(),
        };
        serde_yaml::to_string(&doc).expect("BagMetadata serialises: plain strings and integers")
    }

    /// The `rosbag2_bagfile_information` mapping alone, as rosbag2 stores it in the MCAP
    /// `rosbag2` Metadata record (`serialized_metadata`).
    pub fn to_inner_yaml(&self) -> String {
        serde_yaml::to_string(self).expect("BagMetadata serialises: plain strings and integers")
    }

    pub fn from_yaml(path: &Path, text: &str) -> Result<Self> {
        let doc: MetadataDocument = serde_yaml::from_str(text).map_err(|e| BagError::Metadata {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let m = doc.rosbag2_bagfile_information;
        if m.version == 0 || m.version > 9 {
            return Err(BagError::Metadata {
                path: path.to_path_buf(),
                reason: format!("unsupported rosbag2 metadata version {}", m.version),
            });
        }
        Ok(m)
    }

    /// Read `<dir>/metadata.yaml`.
    pub fn read_dir(dir: &Path) -> Result<Self> {
        let path = dir.join(METADATA_FILE);
        let text = std::fs::read_to_string(&path).map_err(io_err("read", &path))?;
        Self::from_yaml(&path, &text)
    }

    /// Atomically replace `<dir>/metadata.yaml` (write a temp file, optionally fsync, rename),
    /// so a crash never leaves a half-written metadata file.
    pub fn write_dir(&self, dir: &Path, sync: bool) -> Result<PathBuf> {
        let path = dir.join(METADATA_FILE);
        let tmp = dir.join("metadata.yaml.tmp");
        {
            use std::io::Write;
            let mut f = std::fs::File::create(&tmp).map_err(io_err("create", &tmp))?;
            f.write_all(self.to_yaml().as_bytes())
                .map_err(io_err("write", &tmp))?;
            if sync {
                f.sync_all().map_err(io_err("fsync", &tmp))?;
            }
        }
        std::fs::rename(&tmp, &path).map_err(io_err("rename to metadata.yaml", &tmp))?;
        Ok(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_rosbags_v9_sequence_qos() {
        let mut m = BagMetadata::empty();
        m.relative_file_paths.push("b_0.mcap".into());
        m.topics_with_message_count.push(TopicWithMessageCount {
            topic_metadata: TopicMetadata {
                name: "/t".into(),
                type_name: "std_msgs/msg/String".into(),
                serialization_format: "cdr".into(),
                offered_qos_profiles: "- history: 1\n  depth: 10".into(),
                type_description_hash: String::new(),
            },
            message_count: 3,
        });
        let y = m.to_yaml();
        let back = BagMetadata::from_yaml(Path::new("m.yaml"), &y).unwrap();
        assert_eq!(back, m);

        let v9 = "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n  \
                  duration: {nanoseconds: 5}\n  starting_time: {nanoseconds_since_epoch: 7}\n  \
                  message_count: 1\n  topics_with_message_count:\n  - topic_metadata:\n      \
                  name: /a\n      type: x/msg/Y\n      serialization_format: cdr\n      \
                  offered_qos_profiles:\n      - history: keep_last\n        depth: 3\n    \
                  message_count: 1\n  relative_file_paths: [a.mcap]\n  custom_data: null\n";
        let m9 = BagMetadata::from_yaml(Path::new("m.yaml"), v9).unwrap();
        assert_eq!(m9.version, 9);
        assert!(m9.topics_with_message_count[0]
            .topic_metadata
            .offered_qos_profiles
            .contains("keep_last"));
    }

    #[test]
    fn version_10_is_rejected_with_path() {
        let y = "rosbag2_bagfile_information:\n  version: 10\n  storage_identifier: mcap\n  \
                 duration: {nanoseconds: 0}\n  starting_time: {nanoseconds_since_epoch: 0}\n  \
                 message_count: 0\n  topics_with_message_count: []\n  relative_file_paths: []\n";
        let e = BagMetadata::from_yaml(Path::new("/x/metadata.yaml"), y)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/x/metadata.yaml") && e.contains("version 10"),
            "{e}"
        );
    }
}
