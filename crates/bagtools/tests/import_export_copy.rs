//! Import of the shipped Leica-style example, bad-row reporting, CSV export values, filter and
//! merge counts — all through real bag files.

use std::path::{Path, PathBuf};

use metrocell_bag::{BagReader, MessageFilter, WriterOptions};
use metrocell_bagtools::import::{import_csv, Mapping};
use metrocell_bagtools::{export, filter_bag, merge_bags, BagSource, ToolError, TopicSelection};
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_msgs::sensor_msgs::msg::{FluidPressure, RelativeHumidity, Temperature};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bagtools_it_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

fn import_example(dir: &Path) {
    let mapping = Mapping::load(&examples().join("leica_mapping.yaml")).unwrap();
    let r = import_csv(
        &examples().join("leica_export.csv"),
        dir,
        Some(&mapping),
        WriterOptions::default(),
    )
    .unwrap();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert_eq!((r.rows_read, r.rows_imported), (4, 4));
}

#[test]
fn leica_example_imports_unchanged_in_metres() {
    let dir = scratch("leica");
    import_example(&dir);
    let mut src = BagSource::open(&dir).unwrap();
    src.subscribe::<MeasuredPoint>("/measured_points").unwrap();
    let points: Vec<MeasuredPoint> = src
        .messages()
        .unwrap()
        .map(|m| m.unwrap().decode().unwrap())
        .collect();
    assert_eq!(points.len(), 4);
    let p = &points[0];
    assert_eq!(
        (
            p.point_id.as_str(),
            p.header.frame_id.as_str(),
            p.source.as_str()
        ),
        ("P001", "tracker", "leica_tracker")
    );
    assert_eq!(
        (p.measured.x, p.measured.y, p.measured.z),
        (1.2501234, -0.3405, 0.8120001)
    );
    assert_eq!(
        (p.header.stamp.sec, p.header.stamp.nanosec),
        (1_714_557_600, 125_000_000)
    );
    // U95 0.0150 mm, k = 2 → σ = 7.5 µm on each axis
    assert!((p.covariance[0] - 7.5e-6f64.powi(2)).abs() < 1e-24 && p.covariance[1] == 0.0);
    assert_eq!(points[3].measured.y, -0.3404893);

    let mut src = BagSource::open(&dir).unwrap();
    src.subscribe::<Temperature>("/temperature/air").unwrap();
    src.subscribe::<FluidPressure>("/air/pressure").unwrap();
    src.subscribe::<RelativeHumidity>("/air/humidity").unwrap();
    let mut seen = 0;
    for m in src.messages().unwrap() {
        let m = m.unwrap();
        if m.log_time_ns != 1_714_557_602_250_000_000 {
            continue;
        }
        seen += 1;
        match m.topic.as_str() {
            "/temperature/air" => assert_eq!(m.decode::<Temperature>().unwrap().temperature, 20.32),
            "/air/pressure" => assert_eq!(
                m.decode::<FluidPressure>().unwrap().fluid_pressure,
                101324.0
            ),
            "/air/humidity" => assert_eq!(
                m.decode::<RelativeHumidity>().unwrap().relative_humidity,
                0.451
            ),
            other => panic!("unexpected {other}"),
        }
    }
    assert_eq!(seen, 3);
    // Wrong type for a recorded topic is refused, naming the topic.
    let mut src = BagSource::open(&dir).unwrap();
    assert!(src
        .subscribe::<Temperature>("/measured_points")
        .unwrap_err()
        .to_string()
        .contains("/measured_points"));
}

#[test]
fn bad_rows_are_reported_by_line_and_column_and_the_rest_imported() {
    let dir = scratch("badrows");
    let csv = dir.with_extension("csv");
    std::fs::write(
        &csv,
        "timestamp,point_id,measured_x,measured_y,measured_z,u_x,u_y,u_z,temperature.bed\n\
         1714557600.0,A,1.0,2.0,3.0,1e-5,1e-5,1e-5,20.5\n\
         1714557601.0,B,1.x,2.0,3.0,1e-5,1e-5,1e-5,20.5\n\
         1714557602.0,C,1.0,2.0,3.0,1e-5,-1,1e-5,20.5\n\
         yesterday,D,1.0,2.0,3.0,1e-5,1e-5,1e-5,20.5\n\
         1714557604.0,E,1.5,2.5,3.5,2e-5,2e-5,2e-5,\n",
    )
    .unwrap();
    let r = import_csv(&csv, &dir, None, WriterOptions::default()).unwrap();
    assert_eq!((r.rows_read, r.rows_imported, r.rows_rejected()), (5, 2, 3));
    let msgs: Vec<String> = r.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(msgs.len(), 3, "{msgs:?}");
    assert!(
        msgs[0].contains("line 3, column measured_x") && msgs[0].contains("'1.x'"),
        "{}",
        msgs[0]
    );
    assert!(msgs[1].contains("line 4, column u_y"), "{}", msgs[1]);
    assert!(msgs[2].contains("line 5, column timestamp"), "{}", msgs[2]);
    assert!(msgs.iter().all(|m| m.contains(&csv.display().to_string())));
    assert!(matches!(r.errors[0], ToolError::Row { line: 3, .. }));
    assert_eq!(r.messages_per_topic["/measured_points"], 2);
    assert_eq!(
        r.messages_per_topic["/temperature/bed"], 1,
        "empty auxiliary cell writes no message"
    );
}

/// A tool offset is three coordinates: a row with some of them is refused by line and the
/// others imported; the offset is written before the point it applies to, and again only when
/// it changes.
#[test]
fn a_partial_tool_offset_is_refused_and_a_change_is_written_before_its_point() {
    let dir = scratch("tooloffset");
    let csv = dir.with_extension("csv");
    std::fs::write(
        &csv,
        "timestamp,point_id,measured_x,measured_y,measured_z,u95,tool_offset.x,tool_offset.y,tool_offset.z\n\
         1714557600.0,A,1.0,2.0,3.0,1e-5,0,0,-0.1\n\
         1714557601.0,B,1.0,2.0,3.0,1e-5,0,0,-0.1\n\
         1714557602.0,C,1.0,2.0,3.0,1e-5,0.15,,-0.1\n\
         1714557603.0,D,1.0,2.0,3.0,1e-5,0.15,0,-0.1\n",
    )
    .unwrap();
    let r = import_csv(&csv, &dir, None, WriterOptions::default()).unwrap();
    assert_eq!((r.rows_read, r.rows_imported), (4, 3));
    let msg = r.errors[0].to_string();
    assert!(
        msg.contains("line 4, column tool_offset.*") && msg.contains("not all three"),
        "{msg}"
    );
    assert_eq!(r.messages_per_topic["/machine/tool_offset"], 2);
    let reader = BagReader::open(&dir).unwrap();
    let order: Vec<(String, u64)> = reader
        .messages(&MessageFilter::default())
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.topic == "/machine/tool_offset" || m.topic == "/measured_points")
        .map(|m| (m.topic.clone(), m.log_time))
        .collect();
    let topics: Vec<&str> = order.iter().map(|(t, _)| t.as_str()).collect();
    assert_eq!(
        topics,
        [
            "/machine/tool_offset",
            "/measured_points",
            "/measured_points",
            "/machine/tool_offset",
            "/measured_points"
        ]
    );
}

#[test]
fn missing_uncertainty_is_refused() {
    let dir = scratch("nounc");
    let csv = dir.with_extension("csv");
    std::fs::write(
        &csv,
        "timestamp,point_id,measured_x,measured_y,measured_z\n1,A,1,2,3\n",
    )
    .unwrap();
    let e = import_csv(&csv, &dir, None, WriterOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("uncertainty") && e.contains("line 1"), "{e}");
    // Uncertainty for x only: the axes without one are named (before: NaN covariance, no error).
    std::fs::write(
        &csv,
        "timestamp,point_id,measured_x,measured_y,measured_z,u_x\n1,A,1,2,3,0.001\n",
    )
    .unwrap();
    let e = import_csv(&csv, &dir, None, WriterOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no uncertainty column for u_y, u_z ("), "{e}");
}

#[test]
fn export_columns_and_values() {
    let dir = scratch("export_in");
    import_example(&dir);
    let out = scratch("export_out");
    let res = export::export_csv(
        &dir,
        &["/measured_points".into(), "/air/pressure".into()],
        &out,
    )
    .unwrap();
    assert_eq!(res.len(), 2);
    let text = std::fs::read_to_string(out.join("measured_points.csv")).unwrap();
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header.len(), 2 + 3 + 2 + 3 + 3 + 9);
    assert_eq!(
        &header[..7],
        &[
            "log_time_ns",
            "publish_time_ns",
            "header.stamp.sec",
            "header.stamp.nanosec",
            "header.frame_id",
            "point_id",
            "source"
        ]
    );
    assert_eq!(header.last().unwrap(), "covariance.8");
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 4);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    assert_eq!(&rows[2][col("point_id")], "P003");
    assert_eq!(rows[2][col("measured.x")].parse::<f64>().unwrap(), 1.15);
    assert_eq!(rows[2][col("measured.z")].parse::<f64>().unwrap(), 0.811995);
    assert_eq!(&rows[2][col("log_time_ns")], "1714557604375000000");
    let p = std::fs::read_to_string(out.join("air.pressure.csv")).unwrap();
    assert!(p.lines().nth(4).unwrap().ends_with(",101325,0"), "{p}");
    assert!(export::export_csv(&dir, &["/nope".into()], &out)
        .unwrap_err()
        .to_string()
        .contains("/nope"));
}

#[test]
fn filter_and_merge_counts() {
    let a = scratch("merge_a");
    import_example(&a);
    let f = scratch("filtered");
    // topics by regex, time window [t0 + 2 s, t0 + 6 s): rows 2 and 3 (2.25 s and 4.375 s after 10:00:00)
    let t0 = 1_714_557_600_125_000_000u64;
    let r = filter_bag(
        &BagReader::open(&a).unwrap(),
        &f,
        &TopicSelection::new(vec![], "/air/.*", "").unwrap(),
        Some(t0 + 2_000_000_000),
        Some(t0 + 6_000_000_000),
        WriterOptions::default(),
    )
    .unwrap();
    assert_eq!(r.per_topic.len(), 2);
    assert_eq!(
        (
            r.per_topic["/air/pressure"],
            r.per_topic["/air/humidity"],
            r.total()
        ),
        (2, 2, 4)
    );
    assert_eq!(BagReader::open(&f).unwrap().message_count(), 4);

    let m = scratch("merged");
    let r = merge_bags(&m, &[a.as_path(), f.as_path()], WriterOptions::default()).unwrap();
    assert_eq!(r.total(), 16 + 4);
    let all = BagReader::open(&m)
        .unwrap()
        .read_all(&MessageFilter::default())
        .unwrap();
    assert_eq!(all.len(), 20);
    assert!(
        all.windows(2).all(|w| w[0].log_time <= w[1].log_time),
        "merged in log-time order"
    );
}

/// A mapping that maps onto a field the layout does not have is refused naming the mapping file
/// and the key.
#[test]
fn mapping_to_an_unknown_field_names_the_file_and_key() {
    let dir = scratch("badmap");
    let map = dir.with_extension("yaml");
    let text = std::fs::read_to_string(examples().join("leica_mapping.yaml"))
        .unwrap()
        .replace("  u95: {column:", "  u_95: {column:");
    std::fs::write(&map, text).unwrap();
    let mapping = Mapping::load(&map).unwrap();
    let e = import_csv(
        &examples().join("leica_export.csv"),
        &dir,
        Some(&mapping),
        WriterOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains(&map.display().to_string()) && e.contains("columns.u_95"),
        "{e}"
    );
    let _ = std::fs::remove_file(&map);
}
