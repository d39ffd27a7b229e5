//! `bag export`: one CSV file per topic, one column per leaf field.
//!
//! Layout of each file: columns `log_time_ns`, `publish_time_ns`, then every leaf field of the
//! message with a dotted name (`header.stamp.sec`, `measured.x`). Fixed-size arrays are expanded
//! element by element (`covariance.0` … `covariance.8`, `points.0.x` for arrays of messages);
//! variable-size arrays (`T[]`, `T[<=N]`) are one column holding the array as JSON text, so
//! every row of a topic has the same columns. Floats are written in Rust's shortest round-trip
//! form, so parsing a cell gives back the exact f64 that was recorded. The file is named after
//! the topic without the leading `/` and with `/` replaced by `.` (`/tracker/points` →
//! `tracker.points.csv`).
//!
//! The header is written from the type, so a topic without messages exports as a header row.
//! Next to the files, `export.yaml` ([`crate::export_manifest`]) names each file's topic, type,
//! definition and QoS: `bag import DIR` rebuilds the bag from them ([`crate::reimport`]).
//!
//! The same columns, typed, as Parquet: `metrocell_parquet_export` (a crate of its own, so the nodes do not link Parquet).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_bag::{BagReader, MessageFilter, TopicInfo};
use rosmsg::{ArrayKind, Registry, Value};

use crate::error::{io, Result, ToolError};
use crate::export_manifest::{ExportManifest, ManifestTopic};

/// A registry able to decode `topic`: metrocell's own if it knows the type, otherwise one
/// parsed from the definition stored in the bag (so bags from other ROS systems export too).
pub fn registry_for(topic: &TopicInfo) -> Result<std::borrow::Cow<'static, Registry>> {
    registry_for_type(&topic.type_name, &topic.definition).map_err(|reason| ToolError::Topic {
        topic: topic.name.clone(),
        reason,
    })
}

/// A registry able to decode `type_name`: metrocell's own if it knows the type, otherwise one
/// parsed from `definition` (a rosbag2 schema: the type's text, then its dependencies).
pub fn registry_for_type(
    type_name: &str,
    definition: &str,
) -> std::result::Result<std::borrow::Cow<'static, Registry>, String> {
    let own = metrocell_msgs::registry();
    if own.get(type_name).is_some() {
        return Ok(std::borrow::Cow::Borrowed(own));
    }
    let main = rosmsg::TypeName::parse(type_name)
        .ok_or_else(|| format!("type name {type_name} does not parse"))?;
    let mut reg = Registry::new();
    let mut blocks = definition.split(rosmsg::DEFINITION_SEPARATOR);
    reg.add_msg(&main.package, &main.name, blocks.next().unwrap_or_default())
        .map_err(|e| format!("definition of {type_name}: {e}"))?;
    for block in blocks {
        let block = block.trim_start_matches('\n');
        let (first, text) = block.split_once('\n').unwrap_or((block, ""));
        let name = first.trim().strip_prefix("MSG:").ok_or_else(|| {
            format!("dependency block starts with '{first}', not 'MSG: pkg/Type'")
        })?;
        let t = rosmsg::TypeName::parse(name.trim())
            .ok_or_else(|| format!("dependency name '{name}' does not parse"))?;
        if reg.get(&t.to_string()).is_none() {
            reg.add_msg(&t.package, &t.name, text)
                .map_err(|e| format!("definition of {t}: {e}"))?;
        }
    }
    Ok(std::borrow::Cow::Owned(reg))
}

fn scalar_text(v: &Value) -> String {
    match v {
        Value::Bool(b) => b.to_string(),
        Value::Int(i) => i.to_string(),
        Value::UInt(u) => u.to_string(),
        Value::Float(f) => f.to_string(),
        Value::String(s) => s.clone(),
        other => rosmsg::to_json(other).to_string(),
    }
}

fn flatten_into(registry: &Registry, prefix: &str, value: &Value, out: &mut Vec<(String, String)>) {
    let join = |name: &str| {
        if prefix.is_empty() {
            name.to_string()
        } else {
            format!("{prefix}.{name}")
        }
    };
    let Value::Struct(s) = value else {
        out.push((prefix.to_string(), scalar_text(value)));
        return;
    };
    let spec = registry.get(&s.type_name);
    for (i, (name, v)) in s.fields.iter().enumerate() {
        let kind = spec
            .and_then(|sp| sp.fields.get(i))
            .map(|f| f.ty.array)
            .unwrap_or(ArrayKind::Single);
        let col = join(name);
        match (kind, v) {
            (ArrayKind::Fixed(_), Value::Array(items)) => {
                for (j, item) in items.iter().enumerate() {
                    flatten_into(registry, &format!("{col}.{j}"), item, out);
                }
            }
            (_, Value::Array(_)) => out.push((col, rosmsg::to_json(v).to_string())),
            (_, Value::Struct(_)) => flatten_into(registry, &col, v, out),
            _ => out.push((col, scalar_text(v))),
        }
    }
}

/// Leaf fields of a decoded message as (dotted column name, cell text), in `.msg` order.
pub fn flatten(registry: &Registry, value: &Value) -> Vec<(String, String)> {
    let mut out = Vec::new();
    flatten_into(registry, "", value, &mut out);
    out
}

/// File name of a topic's CSV.
pub fn csv_file_name(topic: &str) -> String {
    format!("{}.csv", topic.trim_start_matches('/').replace('/', "."))
}

/// What was exported for one topic.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportedTopic {
    pub path: PathBuf,
    pub rows: u64,
    pub columns: usize,
}

/// The topics of `bag` to export: `topics` in the bag's order (all when empty); a name the bag
/// does not hold is an error listing the topics it does hold.
pub fn chosen_topics<'a>(
    reader: &'a BagReader,
    bag: &Path,
    topics: &[String],
) -> Result<Vec<&'a TopicInfo>> {
    for t in topics {
        if reader.topic(t).is_none() {
            let known: Vec<&str> = reader.topics().iter().map(|t| t.name.as_str()).collect();
            return Err(ToolError::Topic {
                topic: t.clone(),
                reason: format!("not in {} (topics: {})", bag.display(), known.join(", ")),
            });
        }
    }
    Ok(reader
        .topics()
        .iter()
        .filter(|t| topics.is_empty() || topics.contains(&t.name))
        .collect())
}

/// The columns of a topic's export: `log_time_ns`, `publish_time_ns`, then the type's leaf
/// fields — from the type, not from a message, so a topic without messages has them too.
pub fn export_columns(
    registry: &Registry,
    type_name: &str,
) -> std::result::Result<Vec<String>, String> {
    let empty = rosmsg::default_value(registry, type_name).map_err(|e| e.to_string())?;
    let mut columns = vec!["log_time_ns".to_string(), "publish_time_ns".to_string()];
    columns.extend(flatten(registry, &empty).into_iter().map(|c| c.0));
    Ok(columns)
}

/// The manifest entry of an exported topic (see [`crate::export_manifest`]).
pub fn manifest_entry(t: &TopicInfo, path: &Path, rows: u64) -> ManifestTopic {
    ManifestTopic {
        topic: t.name.clone(),
        type_name: t.type_name.clone(),
        file: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        messages: rows,
        offered_qos_profiles: t.offered_qos_profiles.clone(),
        definition: t.definition.clone(),
    }
}

/// Export `topics` (all when empty) of `bag` to CSV files in `out_dir` (created if missing),
/// with the manifest `export.yaml` that lets `bag import` rebuild the bag from them.
pub fn export_csv(
    bag: &Path,
    topics: &[String],
    out_dir: &Path,
) -> Result<BTreeMap<String, ExportedTopic>> {
    let reader = BagReader::open(bag)?;
    let chosen = chosen_topics(&reader, bag, topics)?;
    std::fs::create_dir_all(out_dir).map_err(io(out_dir))?;
    let mut result = BTreeMap::new();
    let mut manifest = ExportManifest {
        bag: bag.display().to_string(),
        format: "csv".into(),
        topics: Vec::new(),
    };
    for t in chosen {
        let registry = registry_for(t)?;
        let path = out_dir.join(csv_file_name(&t.name));
        let file = std::fs::File::create(&path).map_err(io(&path))?;
        let mut w = csv::Writer::from_writer(std::io::BufWriter::new(file));
        let csv_err = |e: csv::Error| ToolError::Io {
            path: path.clone(),
            source: std::io::Error::other(e.to_string()),
        };
        let header =
            export_columns(&registry, &t.type_name).map_err(|reason| ToolError::Topic {
                topic: t.name.clone(),
                reason,
            })?;
        w.write_record(&header).map_err(csv_err)?;
        let mut rows = 0u64;
        let filter = MessageFilter {
            topics: Some(vec![t.name.clone()]),
            ..Default::default()
        };
        for m in reader.messages(&filter)? {
            let m = m?;
            let value =
                rosmsg::decode(&registry, &t.type_name, &m.data).map_err(|e| ToolError::Topic {
                    topic: t.name.clone(),
                    reason: format!("message at log time {} ns does not decode: {e}", m.log_time),
                })?;
            let cells = flatten(&registry, &value);
            if cells.len() + 2 != header.len() {
                return Err(ToolError::Topic {
                    topic: t.name.clone(),
                    reason: format!(
                        "message at log time {} ns has {} fields, its type {}",
                        m.log_time,
                        cells.len(),
                        header.len() - 2
                    ),
                });
            }
            let mut row = vec![m.log_time.to_string(), m.publish_time.to_string()];
            row.extend(cells.into_iter().map(|c| c.1));
            w.write_record(&row).map_err(csv_err)?;
            rows += 1;
        }
        w.flush().map_err(io(&path))?;
        manifest.topics.push(manifest_entry(t, &path, rows));
        result.insert(
            t.name.clone(),
            ExportedTopic {
                path,
                rows,
                columns: header.len(),
            },
        );
    }
    manifest.write(out_dir)?;
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_arrays_expand_and_nested_fields_get_dotted_names() {
        let reg = metrocell_msgs::registry();
        let mut v = rosmsg::default_value(reg, "metrocell_msgs/msg/MeasuredPoint").unwrap();
        if let Value::Struct(s) = &mut v {
            if let Some(Value::Struct(m)) = s.get_mut("measured") {
                *m.get_mut("x").unwrap() = Value::Float(0.1 + 0.2);
            }
        }
        let cells = flatten(reg, &v);
        let names: Vec<&str> = cells.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(
            &names[..4],
            &[
                "header.stamp.sec",
                "header.stamp.nanosec",
                "header.frame_id",
                "point_id"
            ]
        );
        assert!(
            names.contains(&"measured.x")
                && names.contains(&"covariance.0")
                && names.contains(&"covariance.8")
        );
        assert!(!names.contains(&"covariance.9") && !names.contains(&"covariance"));
        let x = &cells.iter().find(|c| c.0 == "measured.x").unwrap().1;
        assert_eq!(
            x.parse::<f64>().unwrap(),
            0.1 + 0.2,
            "round-trip float text"
        );
    }

    #[test]
    fn variable_arrays_are_one_json_column() {
        let reg = metrocell_msgs::registry();
        let v = rosmsg::from_json(
            reg,
            "sensor_msgs/msg/JointState",
            &serde_json::json!({"name": ["a", "b"], "position": [1.5, 2.0]}),
        )
        .unwrap();
        let cells = flatten(reg, &v);
        let get = |n: &str| cells.iter().find(|c| c.0 == n).map(|c| c.1.clone());
        assert_eq!(get("name").as_deref(), Some(r#"["a","b"]"#));
        assert_eq!(get("position").as_deref(), Some("[1.5,2.0]"));
        assert_eq!(get("velocity").as_deref(), Some("[]"));
    }

    #[test]
    fn topic_file_names() {
        assert_eq!(csv_file_name("/tracker/points"), "tracker.points.csv");
    }
}
