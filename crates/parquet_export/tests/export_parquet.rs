//! `export_parquet` read back by pyarrow: every ROS primitive type, strings, fixed and variable
//! arrays, nested and arrays of messages. Column names and values must equal the CSV export of
//! the same bag (the CSV export is the reference layout), and the Arrow types must be the
//! typed ones the module doc promises.
//!
//! Needs Python with pyarrow: `METROCELL_PYTHON=.venv/bin/python cargo test -p metrocell-parquet-export`.

use std::path::{Path, PathBuf};
use std::process::Command;

use metrocell_bag::{BagWriter, WriterOptions};
use metrocell_bagtools::export;
use metrocell_parquet_export as export_parquet;
use serde_json::{json, Value as Json};

const TYPE: &str = "test_msgs/msg/AllTypes";

fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return p.into();
    }
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    assert!(
        p.exists(),
        "no Python with pyarrow: set METROCELL_PYTHON or run tests/run (which creates .venv)"
    );
    p
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bagtools_pq_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn registry() -> rosmsg::Registry {
    let mut reg = rosmsg::Registry::new();
    reg.add_msg("test_msgs", "Inner", "float64 x\nstring label\n")
        .unwrap();
    reg.add_msg(
        "test_msgs",
        "AllTypes",
        "bool b\nbyte by\nchar c\nint8 i8\nuint8 u8\nint16 i16\nuint16 u16\nint32 i32\nuint32 u32\n\
         int64 i64\nuint64 u64\nfloat32 f32\nfloat64 f64\nstring s\nfloat64[3] fixed\nint32[] ints\n\
         string[] names\nuint8[<=4] small\nInner single\nInner[2] pair\nInner[] many\n",
    )
    .unwrap();
    reg
}

fn message(i: i64) -> Json {
    let inner = |k: i64| json!({"x": 0.1 * k as f64, "label": format!("in{k}")});
    json!({
        "b": i % 2 == 0, "by": 255 - i, "c": 65 + i, "i8": -128 + i, "u8": 200 + i, "i16": -32768 + i, "u16": 65535 - i,
        "i32": -2147483648i64 + i, "u32": 4294967295u64 - i as u64, "i64": i64::MIN + i, "u64": u64::MAX - i as u64,
        "f32": 0.1 * i as f64, "f64": 0.1 + 0.2 * i as f64, "s": format!("row {i} – µm"),
        "fixed": [i as f64, -1.5, 1e-300],
        "ints": (0..i).map(|k| k as i32 - 1).collect::<Vec<_>>(),
        "names": (0..i % 3).map(|k| format!("n{k}")).collect::<Vec<_>>(),
        "small": (0..(i % 5)).map(|k| k as u8 * 60).collect::<Vec<_>>(),
        "single": inner(i), "pair": [inner(10 + i), inner(20 + i)],
        "many": (0..i % 2 + 1).map(|k| inner(100 * k)).collect::<Vec<_>>(),
    })
}

#[test]
fn parquet_export_read_by_pyarrow_equals_bag_content_with_typed_columns() {
    let n = 6;
    let t0 = 1_700_000_000_000_000_000u64;
    let dir = bag_of_every_type(n, t0);
    let pq_dir = scratch("pq");
    let exported = export_parquet::export_parquet(&dir, &["/test/all".into()], &pq_dir).unwrap();
    let e = &exported["/test/all"];
    assert_eq!(
        (e.rows, e.path.file_name().unwrap().to_str().unwrap()),
        (n, "test.all.parquet")
    );
    let csv_dir = scratch("csv");
    export::export_csv(&dir, &["/test/all".into()], &csv_dir).unwrap();

    let out = Command::new(python())
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/read_parquet.py"))
        .arg(&e.path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pyarrow failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: Json = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["rows"].as_u64(), Some(n));
    arrow_types_are_typed(&doc);
    cells_equal_the_csv_export(&doc, &csv_dir.join("test.all.csv"));
    values_are_the_written_ones(&doc, t0);
}

/// A bag of `n` messages of the type with every field kind, from `t0` (ns) 1 ms apart.
fn bag_of_every_type(n: u64, t0: u64) -> PathBuf {
    let reg = registry();
    let dir = scratch("bag");
    let mut w = BagWriter::create(&dir, WriterOptions::default()).unwrap();
    w.add_topic("/test/all", TYPE, &reg.full_definition(TYPE).unwrap(), "")
        .unwrap();
    for i in 0..n {
        let v = rosmsg::from_json(&reg, TYPE, &message(i as i64)).unwrap();
        w.write(
            "/test/all",
            t0 + i * 1_000_000,
            t0 + i * 1_000_000 - 7,
            &rosmsg::encode(&reg, TYPE, &v).unwrap(),
        )
        .unwrap();
    }
    w.finish().unwrap();
    dir
}

/// Arrow types: numeric of the field's width and signedness, UTF-8, lists for T[].
fn arrow_types_are_typed(doc: &Json) {
    let types = doc["types"].as_object().unwrap();
    let expect = [
        ("log_time_ns", "int64"),
        ("b", "bool"),
        ("by", "uint8"),
        ("c", "uint8"),
        ("i8", "int8"),
        ("u8", "uint8"),
        ("i16", "int16"),
        ("u16", "uint16"),
        ("i32", "int32"),
        ("u32", "uint32"),
        ("i64", "int64"),
        ("u64", "uint64"),
        ("f32", "float"),
        ("f64", "double"),
        ("s", "string"),
        ("fixed.2", "double"),
        ("ints", "list<element: int32 not null>"),
        ("names", "list<element: string not null>"),
        ("small", "list<element: uint8 not null>"),
        ("single.x", "double"),
        ("pair.1.label", "string"),
        ("many", "string"),
    ];
    for (col, ty) in expect {
        assert_eq!(
            types.get(col).and_then(|t| t.as_str()),
            Some(ty),
            "type of column {col}"
        );
    }
}

/// Same columns in the same order as the CSV export, and equal values cell by cell.
fn cells_equal_the_csv_export(doc: &Json, csv_path: &Path) {
    let types = doc["types"].as_object().unwrap();
    let mut csv = csv::Reader::from_path(csv_path).unwrap();
    let header: Vec<String> = csv.headers().unwrap().iter().map(String::from).collect();
    let pq_names: Vec<String> = serde_json::from_value(doc["names"].clone()).unwrap();
    assert_eq!(
        pq_names, header,
        "same column names, same order as the CSV export"
    );
    for (row, rec) in csv.records().enumerate() {
        let rec = rec.unwrap();
        for (col, cell) in header.iter().zip(rec.iter()) {
            let got = &doc["columns"][col][row];
            let ty = types[col].as_str().unwrap();
            let same = if ty == "string" {
                got.as_str() == Some(cell)
            } else if ty == "bool" {
                got.as_bool().map(|b| b.to_string()).as_deref() == Some(cell)
            } else if ty.starts_with("list") {
                *got == serde_json::from_str::<Json>(cell).unwrap()
            } else if ty == "float" || ty == "double" {
                got.as_f64() == Some(cell.parse::<f64>().unwrap())
            } else if ty == "uint64" {
                got.as_u64() == Some(cell.parse::<u64>().unwrap())
            } else {
                got.as_i64() == Some(cell.parse::<i64>().unwrap())
            };
            assert!(
                same,
                "row {row} column {col}: parquet {got} vs CSV {cell:?}"
            );
        }
    }
}

/// Spot checks against the written values (not through the CSV export).
fn values_are_the_written_ones(doc: &Json, t0: u64) {
    let col = |c: &str| doc["columns"][c].clone();
    assert_eq!(
        col("u64")[0].as_u64(),
        Some(u64::MAX),
        "uint64 keeps its full range"
    );
    assert_eq!(col("u32")[1].as_u64(), Some(4_294_967_294));
    assert_eq!(col("i64")[2].as_i64(), Some(i64::MIN + 2));
    assert_eq!(col("i8")[0].as_i64(), Some(-128));
    assert_eq!(col("f64")[1].as_f64(), Some(0.1 + 0.2), "float64 bit-exact");
    assert_eq!(
        col("f32")[3].as_f64(),
        Some((0.1f64 * 3.0) as f32 as f64),
        "float32 value"
    );
    assert_eq!(col("s")[4].as_str(), Some("row 4 – µm"));
    assert_eq!(
        col("ints")[0],
        json!([]),
        "empty list stays an empty list, not null"
    );
    assert_eq!(col("ints")[3], json!([-1, 0, 1]));
    assert_eq!(col("names")[2], json!(["n0", "n1"]));
    assert_eq!(col("small")[4], json!([0, 60, 120, 180]));
    assert_eq!(col("pair.1.label")[5].as_str(), Some("in25"));
    assert_eq!(col("fixed.2")[0].as_f64(), Some(1e-300));
    let many: Json = serde_json::from_str(col("many")[1].as_str().unwrap()).unwrap();
    assert_eq!(
        many[1]["label"], "in100",
        "arrays of messages are JSON text"
    );
    assert_eq!(
        col("log_time_ns")[5].as_i64(),
        Some((t0 + 5_000_000) as i64)
    );
    assert_eq!(
        col("publish_time_ns")[5].as_i64(),
        Some((t0 + 5_000_000 - 7) as i64)
    );
}

#[test]
fn unknown_topic_is_an_error_naming_the_bag_and_the_topics() {
    let reg = registry();
    let dir = scratch("unknown");
    let mut w = BagWriter::create(&dir, WriterOptions::default()).unwrap();
    w.add_topic("/test/all", TYPE, &reg.full_definition(TYPE).unwrap(), "")
        .unwrap();
    w.finish().unwrap();
    let e = export_parquet::export_parquet(&dir, &["/nope".into()], &scratch("unknown_out"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nope") && e.contains("/test/all"), "{e}");
    // A topic without messages still gets a file with its full schema.
    let out = scratch("empty_out");
    let r = export_parquet::export_parquet(&dir, &[], &out).unwrap();
    assert_eq!(r["/test/all"].rows, 0);
    assert!(r["/test/all"].columns > 20);
}

/// Large messages close row groups by buffered values, not only by rows: each 3 MB image (3 M
/// list values and 6 M Dremel levels, over the 4 M cap) closes its own row group, where the
/// row count alone (64 Ki rows) would have buffered the whole topic; pyarrow reads every byte back.
#[test]
fn large_messages_are_flushed_in_bounded_row_groups() {
    use metrocell_msgs::sensor_msgs::msg::Image;
    use rosmsg::RosMessage;
    let dir = scratch("images");
    let mut w = BagWriter::create(&dir, WriterOptions::default()).unwrap();
    w.add_topic("/img", Image::ROS_TYPE, Image::DEFINITION, "")
        .unwrap();
    let n = 3_000_000usize;
    for k in 0..3u64 {
        let m = Image {
            height: 1000,
            width: 3000,
            encoding: "mono8".into(),
            step: 3000,
            data: (0..n).map(|i| ((i as u64 * 7 + k) % 251) as u8).collect(),
            ..Default::default()
        };
        w.write(
            "/img",
            k + 1,
            k + 1,
            &metrocell_bagtools::encode_cdr(&m).unwrap(),
        )
        .unwrap();
    }
    w.finish().unwrap();
    let out = dir.with_extension("out");
    let done = export_parquet::export_parquet(&dir, &[], &out).unwrap();
    let path = &done["/img"].path;
    let script =
        "import sys, pyarrow.parquet as pq\nf = pq.ParquetFile(sys.argv[1])\nt = f.read()\n\
                  d = t.column('data').to_pylist()\n\
                  print(f.num_row_groups, t.num_rows, [len(x) for x in d], [x[12345] for x in d])";
    let o = Command::new(python())
        .args(["-c", script, path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let expect = |k: u64| (12345u64 * 7 + k) % 251;
    assert_eq!(
        text.trim(),
        format!(
            "3 3 [{n}, {n}, {n}] [{}, {}, {}]",
            expect(0),
            expect(1),
            expect(2)
        )
    );
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&out);
}
