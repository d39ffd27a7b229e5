//! `export.yaml`: what `bag export` writes next to its CSV (or Parquet) files so that `bag
//! import` can rebuild the bag from them without a hand mapping — each file's topic, message
//! type and definition (so types unknown to metrocell rebuild too) and the QoS its publishers
//! offered (so a latched topic stays latched).
//!
//! ```yaml
//! # metrocell bag export of /data/run42 (csv): `metrocell bag import <this directory> -o BAG` rebuilds it
//! bag: /data/run42
//! format: csv
//! topics:
//! - topic: /tracker/power_on
//!   type: sensor_msgs/msg/TimeReference
//!   file: tracker.power_on.csv
//!   messages: 1
//!   offered_qos_profiles: "- history: 1\n  depth: 1\n ..."
//!   definition: "builtin_interfaces/Time time_ref\n..."
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{io, Result, ToolError};

/// The file's name inside an export directory.
pub const MANIFEST_FILE: &str = "export.yaml";

/// One exported topic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManifestTopic {
    pub topic: String,
    #[serde(rename = "type")]
    pub type_name: String,
    /// The file's name, relative to the manifest's directory.
    pub file: String,
    pub messages: u64,
    /// rosbag2's `offered_qos_profiles` text, as the bag stored it ("" when it had none).
    #[serde(default)]
    pub offered_qos_profiles: String,
    /// The type's ros2msg definition as the bag stored it ("" when it had none).
    #[serde(default)]
    pub definition: String,
}

/// The manifest of an export directory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportManifest {
    /// The bag that was exported, as given.
    pub bag: String,
    /// `csv` or `parquet`.
    pub format: String,
    pub topics: Vec<ManifestTopic>,
}

impl ExportManifest {
    /// Write the manifest (`export.yaml`) into `dir`.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        let path = dir.join(MANIFEST_FILE);
        let body = serde_yaml::to_string(self)
            .map_err(|e| ToolError::Invalid(format!("{}: {e}", path.display())))?;
        let text = format!("# metrocell bag export of {} ({}): `metrocell bag import <this directory> -o BAG` rebuilds it\n{body}", self.bag, self.format);
        std::fs::write(&path, text).map_err(io(&path))?;
        Ok(path)
    }

    /// Read the manifest (`export.yaml`) in `dir`; `None` when the directory has none.
    pub fn read(dir: &Path) -> Result<Option<ExportManifest>> {
        let path = dir.join(MANIFEST_FILE);
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&path).map_err(io(&path))?;
        serde_yaml::from_str(&text)
            .map(Some)
            .map_err(|e| ToolError::Mapping {
                path,
                reason: format!("not a `bag export` manifest: {e}"),
            })
    }

    /// The entry of the file called `file_name`, if the manifest lists it.
    pub fn entry(&self, file_name: &str) -> Option<&ManifestTopic> {
        self.topics.iter().find(|t| t.file == file_name)
    }
}

/// The topic a file of an export is named after: `tracker.power_on.csv` → `/tracker/power_on`
/// (ROS names hold no `.`, so the export's `/` → `.` is undone exactly).
pub fn topic_of_file(path: &Path) -> Option<String> {
    let stem = path.file_stem()?.to_str()?;
    (!stem.is_empty()).then(|| format!("/{}", stem.replace('.', "/")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_give_back_their_topics() {
        assert_eq!(
            topic_of_file(Path::new("d/tracker.power_on.csv")).as_deref(),
            Some("/tracker/power_on")
        );
        assert_eq!(
            topic_of_file(Path::new("clock.parquet")).as_deref(),
            Some("/clock")
        );
        assert_eq!(
            topic_of_file(Path::new(crate::export::csv_file_name("/a/b_c/d").as_str())).as_deref(),
            Some("/a/b_c/d")
        );
    }

    #[test]
    fn a_manifest_reads_back_as_written() {
        let dir = std::env::temp_dir().join(format!("metrocell_manifest_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = ExportManifest {
            bag: "run42".into(),
            format: "csv".into(),
            topics: vec![ManifestTopic {
                topic: "/clock".into(),
                type_name: "rosgraph_msgs/msg/Clock".into(),
                file: "clock.csv".into(),
                messages: 3,
                offered_qos_profiles: "- depth: 1\n".into(),
                definition: "builtin_interfaces/Time clock\n".into(),
            }],
        };
        m.write(&dir).unwrap();
        assert_eq!(ExportManifest::read(&dir).unwrap(), Some(m.clone()));
        assert_eq!(
            m.entry("clock.csv").map(|t| t.topic.as_str()),
            Some("/clock")
        );
        assert_eq!(
            ExportManifest::read(&dir.join("nothing_here")).unwrap(),
            None
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
