//! `bag export --format parquet`: one Parquet file per topic, one column per leaf field.
//!
//! A crate of its own so that the nodes, which link `metrocell-bagtools` for offline replay,
//! do not link the `parquet` crate (issue 11 item 7); the `metrocell` command depends on it.
//!
//! Column names and order are those of the CSV export ([`metrocell_bagtools::export`]): `log_time_ns`,
//! `publish_time_ns` (INT64), then every leaf field with a dotted name; fixed-size arrays are
//! expanded element by element (`covariance.0` … `covariance.8`). The difference is that
//! every column is typed, so `pandas.read_parquet` gives numeric dtypes without parsing:
//!
//! | ROS type                         | Parquet column (pyarrow / pandas dtype)             |
//! |----------------------------------|-----------------------------------------------------|
//! | bool                             | BOOLEAN (bool)                                      |
//! | int8/16/32, uint8/16/32, byte, char | INT32 + INTEGER(bits, signed) (int8…uint32)      |
//! | int64, uint64                    | INT64 + INTEGER(64, signed) (int64, uint64)         |
//! | float32, float64                 | FLOAT, DOUBLE (float32, float64)                    |
//! | string, wstring                  | BYTE_ARRAY + STRING (object of str)                 |
//! | `T[]`, `T[<=N]` of primitives/strings | LIST of T (object of numpy arrays per row)     |
//! | `M[]`, `M[<=N]` of messages      | BYTE_ARRAY + STRING holding JSON, as in the CSV     |
//!
//! Variable arrays of primitives are native LIST columns rather than expanded, because their
//! length changes from row to row; pyarrow reads them as `list<element>` and pandas as one
//! numpy array per cell (`np.stack(df["position"])` gives a 2-D array). Arrays of messages stay
//! JSON text: a list of structs would not be flat any more. The schema is derived from the
//! message definition, not from the first message, so an empty array still has its type.
//! Pages are zstd-compressed (the zstd library is already linked for the bag files).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use metrocell_bag::{BagReader, MessageFilter};
use parquet::basic::{Compression, LogicalType, Repetition, Type as Physical, ZstdLevel};
use parquet::data_type::{
    BoolType, ByteArray, ByteArrayType, DoubleType, FloatType, Int32Type, Int64Type,
};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::{Type, TypePtr};
use rosmsg::{ArrayKind, BaseType, Primitive, Registry, Value};

mod read_back;
pub use read_back::parquet_rows;

use metrocell_bagtools::export::{chosen_topics, manifest_entry, registry_for, ExportedTopic};
use metrocell_bagtools::export_manifest::ExportManifest;
use metrocell_bagtools::{io, Result, ToolError};

/// A row group is written when it holds this many rows or [`VALUES_PER_GROUP`] buffered
/// values and levels, whichever comes first: rows bound memory for long bags of small messages,
/// values for large ones (a 5 MP image is 5 M list values, ≈ 40 MB buffered with its levels).
const ROWS_PER_GROUP: usize = 64 * 1024;
const VALUES_PER_GROUP: usize = 4 << 20;

/// Physical storage of one leaf, with the logical annotation pyarrow uses for the dtype.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Leaf {
    Bool,
    /// INT32 with INTEGER(bits, signed); unsigned 32-bit values are stored as their bit pattern.
    I32 {
        bits: i8,
        signed: bool,
    },
    /// INT64 with INTEGER(64, signed); uint64 stored as its bit pattern.
    I64 {
        signed: bool,
    },
    F32,
    F64,
    /// UTF-8 text (strings, and JSON for arrays of messages).
    Text,
}

impl Leaf {
    fn of(base: &BaseType) -> Option<Leaf> {
        use Primitive::*;
        Some(match base {
            BaseType::Primitive(p) => match p {
                Bool => Leaf::Bool,
                Byte | Char | UInt8 => Leaf::I32 {
                    bits: 8,
                    signed: false,
                },
                Int8 => Leaf::I32 {
                    bits: 8,
                    signed: true,
                },
                Int16 => Leaf::I32 {
                    bits: 16,
                    signed: true,
                },
                UInt16 => Leaf::I32 {
                    bits: 16,
                    signed: false,
                },
                Int32 => Leaf::I32 {
                    bits: 32,
                    signed: true,
                },
                UInt32 => Leaf::I32 {
                    bits: 32,
                    signed: false,
                },
                Int64 => Leaf::I64 { signed: true },
                UInt64 => Leaf::I64 { signed: false },
                Float32 => Leaf::F32,
                Float64 => Leaf::F64,
            },
            BaseType::String { .. } | BaseType::WString { .. } => Leaf::Text,
            BaseType::Message(_) => return None,
        })
    }

    fn parquet_type(self, name: &str, repetition: Repetition) -> parquet::errors::Result<Type> {
        let (physical, logical) = match self {
            Leaf::Bool => (Physical::BOOLEAN, None),
            Leaf::I32 { bits, signed } => {
                (Physical::INT32, Some(LogicalType::integer(bits, signed)))
            }
            Leaf::I64 { signed } => (Physical::INT64, Some(LogicalType::integer(64, signed))),
            Leaf::F32 => (Physical::FLOAT, None),
            Leaf::F64 => (Physical::DOUBLE, None),
            Leaf::Text => (Physical::BYTE_ARRAY, Some(LogicalType::String)),
        };
        Type::primitive_type_builder(name, physical)
            .with_repetition(repetition)
            .with_logical_type(logical)
            .build()
    }
}

/// One output column and its buffered values.
#[derive(Debug)]
struct Column {
    name: String,
    leaf: Leaf,
    /// A LIST column (variable array of primitives): values plus Dremel levels.
    list: bool,
    /// A JSON text column (variable array of messages).
    json: bool,
    values: Values,
    def: Vec<i16>,
    rep: Vec<i16>,
}

#[derive(Debug)]
enum Values {
    Bool(Vec<bool>),
    I32(Vec<i32>),
    I64(Vec<i64>),
    F32(Vec<f32>),
    F64(Vec<f64>),
    Text(Vec<ByteArray>),
}

impl Column {
    fn new(name: String, leaf: Leaf, list: bool, json: bool) -> Self {
        let values = match leaf {
            Leaf::Bool => Values::Bool(Vec::new()),
            Leaf::I32 { .. } => Values::I32(Vec::new()),
            Leaf::I64 { .. } => Values::I64(Vec::new()),
            Leaf::F32 => Values::F32(Vec::new()),
            Leaf::F64 => Values::F64(Vec::new()),
            Leaf::Text => Values::Text(Vec::new()),
        };
        Column {
            name,
            leaf,
            list,
            json,
            values,
            def: Vec::new(),
            rep: Vec::new(),
        }
    }

    fn parquet_type(&self) -> parquet::errors::Result<TypePtr> {
        if !self.list {
            return Ok(Arc::new(
                self.leaf.parquet_type(&self.name, Repetition::REQUIRED)?,
            ));
        }
        // The three-level LIST layout of the Parquet spec, which pyarrow reads as list<element>.
        let element = Arc::new(self.leaf.parquet_type("element", Repetition::REQUIRED)?);
        let repeated = Arc::new(
            Type::group_type_builder("list")
                .with_repetition(Repetition::REPEATED)
                .with_fields(vec![element])
                .build()?,
        );
        Ok(Arc::new(
            Type::group_type_builder(&self.name)
                .with_repetition(Repetition::REQUIRED)
                .with_logical_type(Some(LogicalType::List))
                .with_fields(vec![repeated])
                .build()?,
        ))
    }

    /// Append one scalar; `None` when the value does not fit the column's type.
    fn push(&mut self, v: &Value) -> Option<()> {
        match (&mut self.values, v) {
            (Values::Bool(out), Value::Bool(b)) => out.push(*b),
            // `as` keeps the bit pattern of uint32/uint64: the INTEGER(…, unsigned) annotation
            // tells readers to interpret it unsigned.
            (Values::I32(out), Value::Int(i)) => out.push(*i as i32),
            (Values::I32(out), Value::UInt(u)) => out.push(*u as u32 as i32),
            (Values::I64(out), Value::Int(i)) => out.push(*i),
            (Values::I64(out), Value::UInt(u)) => out.push(*u as i64),
            (Values::F32(out), Value::Float(f)) => out.push(*f as f32),
            (Values::F64(out), Value::Float(f)) => out.push(*f),
            (Values::Text(out), Value::String(s)) => out.push(ByteArray::from(s.as_str())),
            _ => return None,
        }
        Some(())
    }

    /// Values and Dremel levels held for the next row group.
    fn buffered(&self) -> usize {
        let values = match &self.values {
            Values::Bool(v) => v.len(),
            Values::I32(v) => v.len(),
            Values::I64(v) => v.len(),
            Values::F32(v) => v.len(),
            Values::F64(v) => v.len(),
            Values::Text(v) => v.len(),
        };
        values + self.def.len() + self.rep.len()
    }

    fn clear(&mut self) {
        self.def.clear();
        self.rep.clear();
        match &mut self.values {
            Values::Bool(v) => v.clear(),
            Values::I32(v) => v.clear(),
            Values::I64(v) => v.clear(),
            Values::F32(v) => v.clear(),
            Values::F64(v) => v.clear(),
            Values::Text(v) => v.clear(),
        }
    }
}

/// The columns of a message type, in the CSV export's order (without the two time columns).
fn plan(
    registry: &Registry,
    type_name: &str,
    prefix: &str,
    out: &mut Vec<Column>,
) -> std::result::Result<(), String> {
    let spec = registry
        .get(type_name)
        .ok_or_else(|| format!("type {type_name} is not in the registry"))?;
    for f in &spec.fields {
        let col = if prefix.is_empty() {
            f.name.clone()
        } else {
            format!("{prefix}.{}", f.name)
        };
        let leaf = Leaf::of(&f.ty.base);
        let nested = match &f.ty.base {
            BaseType::Message(t) => Some(t.to_string()),
            _ => None,
        };
        match (f.ty.array, leaf, nested) {
            (ArrayKind::Single, Some(l), _) => out.push(Column::new(col, l, false, false)),
            (ArrayKind::Single, None, Some(t)) => plan(registry, &t, &col, out)?,
            (ArrayKind::Fixed(n), Some(l), _) => {
                (0..n).for_each(|j| out.push(Column::new(format!("{col}.{j}"), l, false, false)))
            }
            (ArrayKind::Fixed(n), None, Some(t)) => {
                for j in 0..n {
                    plan(registry, &t, &format!("{col}.{j}"), out)?;
                }
            }
            (_, Some(l), _) => out.push(Column::new(col, l, true, false)),
            (_, None, _) => out.push(Column::new(col, Leaf::Text, false, true)),
        }
    }
    Ok(())
}

/// Append one decoded message to `columns` (laid out by [`plan`]) starting at `*next`.
fn fill(
    value: &Value,
    columns: &mut [Column],
    next: &mut usize,
) -> std::result::Result<(), String> {
    let Value::Struct(s) = value else {
        return Err("expected a message value".into());
    };
    for (name, v) in &s.fields {
        let c = columns
            .get(*next)
            .ok_or_else(|| format!("field {name} has no column"))?;
        let (list, json, at) = (c.list, c.json, *next);
        // built only on the error path (this loop runs per field of every message)
        let mismatch = |columns: &[Column]| {
            format!(
                "field {name} does not match column {} ({:?})",
                columns[at].name, columns[at].leaf
            )
        };
        match v {
            Value::Array(_) if json => {
                let text = rosmsg::to_json(v).to_string();
                columns[*next]
                    .push(&Value::String(text))
                    .ok_or(())
                    .map_err(|_| mismatch(columns))?;
                *next += 1;
            }
            Value::Array(items) if list => {
                let c = &mut columns[*next];
                if items.is_empty() {
                    // Dremel levels of an empty list: defined up to the list, no element.
                    c.def.push(0);
                    c.rep.push(0);
                }
                for (j, item) in items.iter().enumerate() {
                    if c.push(item).is_none() {
                        return Err(mismatch(columns));
                    }
                    c.def.push(1);
                    c.rep.push(if j == 0 { 0 } else { 1 });
                }
                *next += 1;
            }
            Value::Array(items) => {
                for item in items {
                    if let Value::Struct(_) = item {
                        fill(item, columns, next)?;
                    } else {
                        let c = columns
                            .get_mut(*next)
                            .ok_or_else(|| format!("element of {name} has no column"))?;
                        let n = c.name.clone();
                        c.push(item).ok_or_else(|| {
                            format!("element of {name} does not match column {n}")
                        })?;
                        *next += 1;
                    }
                }
            }
            Value::Struct(_) => fill(v, columns, next)?,
            scalar => {
                columns[*next]
                    .push(scalar)
                    .ok_or(())
                    .map_err(|_| mismatch(columns))?;
                *next += 1;
            }
        }
    }
    Ok(())
}

fn write_group<W: std::io::Write + Send>(
    writer: &mut SerializedFileWriter<W>,
    columns: &mut [Column],
) -> parquet::errors::Result<()> {
    let mut group = writer.next_row_group()?;
    let mut iter = columns.iter_mut();
    while let Some(mut cw) = group.next_column()? {
        let c = iter.next().expect("one parquet leaf per planned column");
        let (def, rep) = if c.list {
            (Some(&c.def[..]), Some(&c.rep[..]))
        } else {
            (None, None)
        };
        match &c.values {
            Values::Bool(v) => cw.typed::<BoolType>().write_batch(v, def, rep)?,
            Values::I32(v) => cw.typed::<Int32Type>().write_batch(v, def, rep)?,
            Values::I64(v) => cw.typed::<Int64Type>().write_batch(v, def, rep)?,
            Values::F32(v) => cw.typed::<FloatType>().write_batch(v, def, rep)?,
            Values::F64(v) => cw.typed::<DoubleType>().write_batch(v, def, rep)?,
            Values::Text(v) => cw.typed::<ByteArrayType>().write_batch(v, def, rep)?,
        };
        cw.close()?;
        c.clear();
    }
    group.close()?;
    Ok(())
}

/// File name of a topic's Parquet file (`/tracker/points` → `tracker.points.parquet`).
pub fn parquet_file_name(topic: &str) -> String {
    format!(
        "{}.parquet",
        topic.trim_start_matches('/').replace('/', ".")
    )
}

/// Export `topics` (all when empty) of `bag` to Parquet files in `out_dir` (created if missing),
/// with the manifest `export.yaml` that lets `bag import` rebuild the bag from them
/// ([`parquet_rows`] reads them back).
pub fn export_parquet(
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
        format: "parquet".into(),
        topics: Vec::new(),
    };
    for t in chosen {
        let registry = registry_for(t)?;
        let bad = |reason: String| ToolError::Topic {
            topic: t.name.clone(),
            reason,
        };
        let mut columns = vec![
            Column::new(
                "log_time_ns".into(),
                Leaf::I64 { signed: true },
                false,
                false,
            ),
            Column::new(
                "publish_time_ns".into(),
                Leaf::I64 { signed: true },
                false,
                false,
            ),
        ];
        plan(&registry, &t.type_name, "", &mut columns)
            .map_err(|e| bad(format!("no Parquet schema: {e}")))?;
        let path = out_dir.join(parquet_file_name(&t.name));
        let pq_err = |e: parquet::errors::ParquetError| ToolError::Io {
            path: path.clone(),
            source: std::io::Error::other(e.to_string()),
        };
        let fields = columns
            .iter()
            .map(Column::parquet_type)
            .collect::<parquet::errors::Result<Vec<_>>>()
            .map_err(pq_err)?;
        let schema = Arc::new(
            Type::group_type_builder("schema")
                .with_fields(fields)
                .build()
                .map_err(pq_err)?,
        );
        let props = WriterProperties::builder()
            .set_compression(Compression::ZSTD(ZstdLevel::default()))
            .build();
        let file = std::fs::File::create(&path).map_err(io(&path))?;
        let mut writer =
            SerializedFileWriter::new(std::io::BufWriter::new(file), schema, Arc::new(props))
                .map_err(pq_err)?;
        let (mut rows, mut buffered) = (0u64, 0usize);
        let filter = MessageFilter {
            topics: Some(vec![t.name.clone()]),
            ..Default::default()
        };
        for m in reader.messages(&filter)? {
            let m = m?;
            let value = rosmsg::decode(&registry, &t.type_name, &m.data).map_err(|e| {
                bad(format!(
                    "message at log time {} ns does not decode: {e}",
                    m.log_time
                ))
            })?;
            columns[0].push(&Value::Int(m.log_time as i64));
            columns[1].push(&Value::Int(m.publish_time as i64));
            let mut next = 2;
            fill(&value, &mut columns, &mut next)
                .map_err(|e| bad(format!("message at log time {} ns: {e}", m.log_time)))?;
            if next != columns.len() {
                return Err(bad(format!(
                    "message at log time {} ns filled {next} of {} columns",
                    m.log_time,
                    columns.len()
                )));
            }
            rows += 1;
            buffered += 1;
            if buffered == ROWS_PER_GROUP
                || columns.iter().map(Column::buffered).sum::<usize>() >= VALUES_PER_GROUP
            {
                write_group(&mut writer, &mut columns).map_err(pq_err)?;
                buffered = 0;
            }
        }
        if buffered > 0 || rows == 0 {
            write_group(&mut writer, &mut columns).map_err(pq_err)?;
        }
        writer.close().map_err(pq_err)?;
        manifest.topics.push(manifest_entry(t, &path, rows));
        result.insert(
            t.name.clone(),
            ExportedTopic {
                path,
                rows,
                columns: columns.len(),
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
    fn plan_matches_csv_names_and_types() {
        let reg = metrocell_msgs::registry();
        let mut cols = Vec::new();
        plan(reg, "sensor_msgs/msg/JointState", "", &mut cols).unwrap();
        let names: Vec<&str> = cols.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "header.stamp.sec",
                "header.stamp.nanosec",
                "header.frame_id",
                "name",
                "position",
                "velocity",
                "effort"
            ]
        );
        assert_eq!(
            cols[0].leaf,
            Leaf::I32 {
                bits: 32,
                signed: true
            }
        );
        assert_eq!(
            cols[1].leaf,
            Leaf::I32 {
                bits: 32,
                signed: false
            }
        );
        assert!(cols[3].list && cols[3].leaf == Leaf::Text);
        assert!(cols[4].list && cols[4].leaf == Leaf::F64);

        let v = rosmsg::default_value(reg, "metrocell_msgs/msg/MeasuredPoint").unwrap();
        let mut cols = Vec::new();
        plan(reg, "metrocell_msgs/msg/MeasuredPoint", "", &mut cols).unwrap();
        let csv_names: Vec<String> = metrocell_bagtools::export::flatten(reg, &v)
            .into_iter()
            .map(|c| c.0)
            .collect();
        let names: Vec<String> = cols.iter().map(|c| c.name.clone()).collect();
        assert_eq!(names, csv_names, "same columns as the CSV export");
    }

    #[test]
    fn lists_get_dremel_levels_and_empty_lists_one_null_slot() {
        let reg = metrocell_msgs::registry();
        let mut cols = Vec::new();
        plan(reg, "sensor_msgs/msg/JointState", "", &mut cols).unwrap();
        let v = rosmsg::from_json(
            reg,
            "sensor_msgs/msg/JointState",
            &serde_json::json!({"name": ["a", "b"], "position": [1.5, 2.0, 3.0]}),
        )
        .unwrap();
        let mut next = 0;
        fill(&v, &mut cols, &mut next).unwrap();
        assert_eq!(next, cols.len());
        assert_eq!(
            (cols[4].def.clone(), cols[4].rep.clone()),
            (vec![1, 1, 1], vec![0, 1, 1])
        );
        assert_eq!(
            (cols[5].def.clone(), cols[5].rep.clone()),
            (vec![0], vec![0]),
            "empty velocity"
        );
        let Values::F64(p) = &cols[4].values else {
            panic!()
        };
        assert_eq!(p, &[1.5, 2.0, 3.0]);
    }
}
