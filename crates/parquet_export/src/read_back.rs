//! `bag import` of a Parquet export: each file's rows as the text cells of the CSV export, so
//! that [`metrocell_bagtools::reimport`] rebuilds the messages the same way from either format.
//! Numbers are written in Rust's shortest round-trip text (float32 columns through their exact
//! f64), LIST columns as the JSON array the CSV holds, strings (and the JSON text of arrays of
//! messages) as they are.

use std::path::Path;

use metrocell_bagtools::reimport::RowSource;
use metrocell_bagtools::{io, Result, ToolError};
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::Field;

/// A Parquet export file's column names and rows (row numbers from 1).
pub fn parquet_rows(path: &Path) -> Result<(Vec<String>, RowSource)> {
    let bad = |e: parquet::errors::ParquetError| {
        ToolError::Invalid(format!(
            "{}: not a readable Parquet file: {e}",
            path.display()
        ))
    };
    let file = std::fs::File::open(path).map_err(io(path))?;
    let reader = SerializedFileReader::new(file).map_err(bad)?;
    let header: Vec<String> = reader
        .metadata()
        .file_metadata()
        .schema_descr()
        .root_schema()
        .get_fields()
        .iter()
        .map(|f| f.name().to_string())
        .collect();
    let owned = path.to_path_buf();
    let rows = reader.into_iter().enumerate().map(move |(i, row)| {
        let line = i as u64 + 1;
        let row = row.map_err(|e| ToolError::Row {
            path: owned.clone(),
            line,
            column: "-".into(),
            reason: e.to_string(),
        })?;
        let cells = row
            .get_column_iter()
            .map(|(name, field)| {
                cell_text(field).map_err(|reason| ToolError::Row {
                    path: owned.clone(),
                    line,
                    column: name.clone(),
                    reason,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok((line, cells))
    });
    Ok((header, Box::new(rows)))
}

/// A cell as the CSV export writes it.
fn cell_text(field: &Field) -> std::result::Result<String, String> {
    Ok(match field {
        Field::Str(s) => s.clone(),
        Field::ListInternal(list) => serde_json::Value::Array(
            list.elements()
                .iter()
                .map(element_json)
                .collect::<std::result::Result<_, _>>()?,
        )
        .to_string(),
        // Rust's shortest round-trip text, as the CSV (and `NaN`, `inf`)
        Field::Float(v) => (*v as f64).to_string(),
        Field::Double(v) => v.to_string(),
        other => match element_json(other)? {
            serde_json::Value::String(s) => s,
            v => v.to_string(),
        },
    })
}

/// A scalar as the JSON the CSV export writes for it (non-finite floats as "nan", "inf", "-inf").
fn element_json(field: &Field) -> std::result::Result<serde_json::Value, String> {
    let float = |v: f64| match serde_json::Number::from_f64(v) {
        Some(n) => serde_json::Value::Number(n),
        None if v.is_nan() => "nan".into(),
        None if v > 0.0 => "inf".into(),
        None => "-inf".into(),
    };
    Ok(match field {
        Field::Bool(b) => (*b).into(),
        Field::Byte(v) => (*v).into(),
        Field::Short(v) => (*v).into(),
        Field::Int(v) => (*v).into(),
        Field::Long(v) => (*v).into(),
        Field::UByte(v) => (*v).into(),
        Field::UShort(v) => (*v).into(),
        Field::UInt(v) => (*v).into(),
        Field::ULong(v) => (*v).into(),
        Field::Float(v) => float(*v as f64),
        Field::Double(v) => float(*v),
        Field::Str(s) => s.clone().into(),
        other => {
            return Err(format!(
                "a {other:?} cell is not something `bag export` writes"
            ))
        }
    })
}
