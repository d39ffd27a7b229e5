//! `bag import` of what `bag export` wrote: the files of an export (CSV here; Parquet rows come
//! in as text cells from `metrocell-parquet-export`) rebuilt into a bag, every message as it was
//! recorded — the same fields (header stamps included), the same log and publish times (the
//! `log_time_ns` / `publish_time_ns` columns), each topic with its type, definition and QoS from
//! the export's manifest ([`crate::export_manifest`]). Without the manifest (one CSV copied
//! elsewhere) the topic comes from the file name and the type from the header: the one message
//! type metrocell knows whose columns it is.
//!
//! Each cell is read back by the kind of its field: floats in Rust's shortest round-trip text
//! (exact, `NaN` and `inf` included), integers, booleans, strings, and variable-length arrays as
//! the JSON text the export wrote. Topics are merged by log time as the rows are read, so the
//! rebuilt bag's chunks follow time as a recorded bag's do.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use rosmsg::{Registry, Value};

use crate::error::{io, Result, ToolError};
use crate::export::{export_columns, registry_for_type};
use crate::export_manifest::{topic_of_file, ManifestTopic};
use crate::import::ImportReport;

/// One row of an exported file: its line (CSV) or row number (Parquet), and its cells as text.
pub type Row = (u64, Vec<String>);

/// The rows of one exported file, in file order (which is log-time order).
pub type RowSource = Box<dyn Iterator<Item = Result<Row>>>;

/// One exported file to rebuild a topic from.
pub struct ExportedFile {
    pub path: PathBuf,
    /// Topic, type, definition and QoS (from the manifest, or inferred).
    pub topic: ManifestTopic,
    pub header: Vec<String>,
    pub rows: RowSource,
}

/// Whether a header is `bag export`'s layout (its two time columns first).
pub fn is_export_header(header: &[String]) -> bool {
    header.len() >= 2 && header[0] == "log_time_ns" && header[1] == "publish_time_ns"
}

/// A CSV file's header and rows.
pub fn csv_rows(path: &Path) -> Result<(Vec<String>, RowSource)> {
    let file = std::fs::File::open(path).map_err(io(path))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(std::io::BufReader::new(file));
    let bad = |e: csv::Error| ToolError::Row {
        path: path.to_path_buf(),
        line: e.position().map_or(1, |p| p.line()),
        column: "-".into(),
        reason: e.to_string(),
    };
    let header = reader
        .headers()
        .map_err(bad)?
        .iter()
        .map(str::to_string)
        .collect();
    let owned = path.to_path_buf();
    let rows = reader.into_records().map(move |r| match r {
        Ok(record) => Ok((
            record.position().map_or(0, |p| p.line()),
            record.iter().map(str::to_string).collect(),
        )),
        Err(e) => Err(ToolError::Row {
            path: owned.clone(),
            line: e.position().map_or(0, |p| p.line()),
            column: "-".into(),
            reason: e.to_string(),
        }),
    });
    Ok((header, Box::new(rows)))
}

/// The topic of an exported file that has no manifest beside it: the topic from the file name,
/// the type the one metrocell message type whose export columns are `header`.
pub fn inferred_topic(path: &Path, header: &[String]) -> Result<ManifestTopic> {
    let registry = metrocell_msgs::registry();
    let matching: Vec<String> = registry
        .ros_type_names()
        .into_iter()
        .filter(|t| export_columns(registry, t).is_ok_and(|c| c == header))
        .collect();
    let bad = |reason: String| ToolError::Invalid(format!("{}: {reason}", path.display()));
    let type_name = match matching.as_slice() {
        [one] => one.clone(),
        [] => return Err(bad("a `bag export` file without its export.yaml, whose columns are no message type metrocell knows: import the whole export directory (its export.yaml names every file's type)".into())),
        many => return Err(bad(format!("a `bag export` file without its export.yaml, whose columns fit several types ({}): import the whole export directory (its export.yaml names every file's type)", many.join(", ")))),
    };
    let topic = topic_of_file(path).ok_or_else(|| bad("the file name gives no topic".into()))?;
    let definition = registry.full_definition(&type_name).unwrap_or_default();
    Ok(ManifestTopic {
        topic,
        type_name,
        file: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        messages: 0,
        offered_qos_profiles: String::new(),
        definition,
    })
}

/// How a column's text becomes its field's value.
#[derive(Clone, Copy)]
enum Leaf {
    Float,
    Int,
    UInt,
    Bool,
    Text,
    /// A variable-length array, as JSON text.
    Json,
}

/// Messages of one type from rows of one header: a JSON template of the default message and,
/// per column after the two times, where its value goes and how it is read.
struct MessageLayout {
    registry: Cow<'static, Registry>,
    type_name: String,
    template: serde_json::Value,
    columns: Vec<(String, Leaf)>,
}

impl MessageLayout {
    fn new(topic: &ManifestTopic, header: &[String]) -> std::result::Result<Self, String> {
        let registry = registry_for_type(&topic.type_name, &topic.definition)?;
        let empty =
            rosmsg::default_value(&registry, &topic.type_name).map_err(|e| e.to_string())?;
        let mut columns = Vec::new();
        for name in &header[2..] {
            let leaf = match empty.at_path(name) {
                Some(Value::Float(_)) => Leaf::Float,
                Some(Value::Int(_)) => Leaf::Int,
                Some(Value::UInt(_)) => Leaf::UInt,
                Some(Value::Bool(_)) => Leaf::Bool,
                Some(Value::String(_)) => Leaf::Text,
                Some(Value::Array(_)) => Leaf::Json,
                _ => {
                    return Err(format!(
                        "column `{name}` is not a field of {}",
                        topic.type_name
                    ))
                }
            };
            columns.push((format!("/{}", name.replace('.', "/")), leaf));
        }
        Ok(Self {
            template: rosmsg::to_json(&empty),
            registry,
            type_name: topic.type_name.clone(),
            columns,
        })
    }

    /// The CDR bytes of the message a row's cells (after the two times) describe; an error names
    /// the column.
    fn encode(
        &self,
        header: &[String],
        cells: &[String],
    ) -> std::result::Result<Vec<u8>, (String, String)> {
        let mut json = self.template.clone();
        for (k, ((pointer, leaf), text)) in self.columns.iter().zip(cells).enumerate() {
            let column = || header[k + 2].clone();
            let value = cell_json(*leaf, text).map_err(|reason| (column(), reason))?;
            *json
                .pointer_mut(pointer)
                .ok_or_else(|| (column(), "no such field".to_string()))? = value;
        }
        let value = rosmsg::from_json(&self.registry, &self.type_name, &json)
            .map_err(|e| ("-".to_string(), e.to_string()))?;
        rosmsg::encode(&self.registry, &self.type_name, &value)
            .map_err(|e| ("-".to_string(), e.to_string()))
    }
}

fn cell_json(leaf: Leaf, text: &str) -> std::result::Result<serde_json::Value, String> {
    let not = |what: &str| format!("'{text}' is not {what}");
    Ok(match leaf {
        Leaf::Float => {
            let v: f64 = text.trim().parse().map_err(|_| not("a number"))?;
            match serde_json::Number::from_f64(v) {
                Some(n) => serde_json::Value::Number(n),
                None if v.is_nan() => "nan".into(),
                None if v > 0.0 => "inf".into(),
                None => "-inf".into(),
            }
        }
        Leaf::Int => text
            .trim()
            .parse::<i64>()
            .map_err(|_| not("an integer"))?
            .into(),
        Leaf::UInt => text
            .trim()
            .parse::<u64>()
            .map_err(|_| not("a non-negative integer"))?
            .into(),
        Leaf::Bool => text
            .trim()
            .parse::<bool>()
            .map_err(|_| not("true or false"))?
            .into(),
        Leaf::Text => text.into(),
        Leaf::Json => {
            serde_json::from_str(text).map_err(|e| format!("'{text}' is not a JSON array: {e}"))?
        }
    })
}

/// A file being merged: its layout and its next row, parsed.
struct Pending {
    file: ExportedFile,
    layout: MessageLayout,
    next: Option<(u64, u64, u64, Vec<String>)>,
}

impl Pending {
    /// Read rows until one has valid times (bad ones are reported and skipped) or the file ends.
    fn advance(&mut self, report: &mut ImportReport) {
        self.next = None;
        while let Some(row) = self.file.rows.next() {
            let (line, cells) = match row {
                Ok(r) => r,
                Err(e) => {
                    report.rows_read += 1;
                    report.errors.push(e);
                    continue;
                }
            };
            report.rows_read += 1;
            let time = |k: usize| cells.get(k).and_then(|c| c.trim().parse::<u64>().ok());
            match (time(0), time(1)) {
                (Some(log), Some(publish)) if cells.len() == self.file.header.len() => {
                    self.next = Some((log, publish, line, cells));
                    return;
                }
                (Some(_), Some(_)) => report.errors.push(self.row_error(
                    line,
                    "-",
                    format!(
                        "{} cells, the header has {}",
                        cells.len(),
                        self.file.header.len()
                    ),
                )),
                _ => report.errors.push(self.row_error(
                    line,
                    "log_time_ns",
                    "log_time_ns and publish_time_ns must be integers (ns since the epoch)".into(),
                )),
            }
        }
    }

    fn row_error(&self, line: u64, column: &str, reason: String) -> ToolError {
        ToolError::Row {
            path: self.file.path.clone(),
            line,
            column: column.into(),
            reason,
        }
    }
}

/// Rebuild the bag `output` (must not exist yet) from exported files: every row a message at
/// its recorded log and publish time. Bad rows are reported (file, line, column) and skipped.
pub fn rebuild_bag(
    files: Vec<ExportedFile>,
    output: &Path,
    options: WriterOptions,
) -> Result<ImportReport> {
    let mut report = ImportReport::default();
    let mut pending = Vec::new();
    for file in files {
        if !is_export_header(&file.header) {
            return Err(ToolError::Invalid(format!("{}: not a `bag export` file (its header does not start with log_time_ns,publish_time_ns)", file.path.display())));
        }
        let layout = MessageLayout::new(&file.topic, &file.header)
            .map_err(|e| ToolError::Invalid(format!("{}: {e}", file.path.display())))?;
        pending.push(Pending {
            file,
            layout,
            next: None,
        });
    }
    let mut writer = BagWriter::create(output, options)?;
    let default_qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    let mut counts: BTreeMap<String, u64> = BTreeMap::new();
    for p in pending.iter_mut() {
        let t = &p.file.topic;
        let qos = if t.offered_qos_profiles.is_empty() {
            &default_qos
        } else {
            &t.offered_qos_profiles
        };
        if t.definition.is_empty() {
            writer.add_topic_without_definition(&t.topic, &t.type_name, qos)?;
        } else {
            writer.add_topic(&t.topic, &t.type_name, &t.definition, qos)?;
        }
        counts.insert(t.topic.clone(), 0);
        p.advance(&mut report);
    }
    // k-way merge by log time; ties keep the files' order
    while let Some(i) = (0..pending.len())
        .filter(|&i| pending[i].next.is_some())
        .min_by_key(|&i| pending[i].next.as_ref().map(|n| n.0))
    {
        let (log, publish, line, cells) = pending[i].next.take().expect("filtered on is_some");
        let p = &pending[i];
        match p.layout.encode(&p.file.header, &cells[2..]) {
            Ok(bytes) => {
                writer.write(&p.file.topic.topic, log, publish, &bytes)?;
                *counts.entry(p.file.topic.topic.clone()).or_default() += 1;
                report.rows_imported += 1;
            }
            Err((column, reason)) => report.errors.push(p.row_error(line, &column, reason)),
        }
        pending[i].advance(&mut report);
    }
    writer.finish()?;
    report.messages_per_topic = counts;
    Ok(report)
}
