//! What arrives as bytes: CDR messages of every type metrocell ships (decoded by the registry's
//! dynamic decoder, as `bag echo`, `bag export` and the dashboard do), MCAP files read strictly
//! and tolerantly, `bag recover` on a damaged file, and the CSV importer with its mapping.

use bolero::check;
use metrocell_bag::{BagReader, MessageFilter, ReadMode, WriterOptions};
use metrocell_fuzz::limits::{bounded, report};
use metrocell_fuzz::{bytes, mutate, workspace_root};
use std::path::{Path, PathBuf};

fn registry() -> rosmsg::Registry {
    let mut r = rosmsg::Registry::new();
    r.add_tree(&workspace_root().join("msgs/interfaces"))
        .unwrap();
    // metrocell's own types (msgs/msg: the package directory is msgs itself)
    let mut own: Vec<PathBuf> = std::fs::read_dir(workspace_root().join("msgs/msg"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    own.sort();
    // dependencies first: add until nothing more can be
    for _ in 0..own.len() {
        own.retain(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().to_string();
            let text = std::fs::read_to_string(p).unwrap();
            r.add_msg("metrocell_msgs", &name, &text).is_err()
        });
    }
    r
}

/// A valid CDR message of `type_name` (every field set), to mutate from.
fn sample_cdr(r: &rosmsg::Registry, type_name: &str) -> Vec<u8> {
    let v = rosmsg::sample_value(r, type_name, 1).unwrap();
    rosmsg::encode(r, type_name, &v).unwrap()
}

#[test]
fn cdr_of_every_message_type() {
    let r = registry();
    let types: Vec<String> = r.type_names().map(|t| t.to_string()).collect();
    assert!(types.len() > 20, "{types:?}");
    let seeds: Vec<Vec<u8>> = types.iter().map(|t| sample_cdr(&r, t)).collect();
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("cdr_of_every_message_type", input, || {
                let k = input.first().map_or(0, |b| usize::from(*b) % types.len());
                let bytes = mutate(&seeds[k], input.get(1..).unwrap_or(&[]));
                let _ = rosmsg::decode(&r, &types[k], &bytes);
            })
        });
    println!("{}", report("cdr_of_every_message_type"));
}

/// Decodes `bytes` as `T` the way a node does a peer's sample (RustDDS's CDR deserializer, through
/// the bag source's decoder, which also honours the encapsulation header).
fn typed<T: rosmsg::RosMessage>(bytes: &[u8]) {
    let m = metrocell_bagtools::SourcedMessage {
        topic: "/fuzz".into(),
        log_time_ns: 0,
        publish_time_ns: 0,
        payload: bytes.to_vec(),
    };
    let _ = m.decode::<T>();
}

#[test]
fn cdr_into_the_types_nodes_decode() {
    use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
    use metrocell_msgs::msg::{
        ErrorModel, FiducialDetectionArray, MeasuredPoint, ProbeHit, TrackerMeasurement,
    };
    use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image, JointState, Temperature};
    type Decode = fn(&[u8]);
    let types: [(&str, Decode); 10] = [
        ("sensor_msgs/msg/Image", typed::<Image>),
        ("sensor_msgs/msg/CameraInfo", typed::<CameraInfo>),
        ("sensor_msgs/msg/JointState", typed::<JointState>),
        ("sensor_msgs/msg/Temperature", typed::<Temperature>),
        (
            "diagnostic_msgs/msg/DiagnosticArray",
            typed::<DiagnosticArray>,
        ),
        ("metrocell_msgs/msg/ErrorModel", typed::<ErrorModel>),
        (
            "metrocell_msgs/msg/FiducialDetectionArray",
            typed::<FiducialDetectionArray>,
        ),
        ("metrocell_msgs/msg/MeasuredPoint", typed::<MeasuredPoint>),
        ("metrocell_msgs/msg/ProbeHit", typed::<ProbeHit>),
        (
            "metrocell_msgs/msg/TrackerMeasurement",
            typed::<TrackerMeasurement>,
        ),
    ];
    let r = registry();
    let seeds: Vec<Vec<u8>> = types.iter().map(|(t, _)| sample_cdr(&r, t)).collect();
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("cdr_into_the_types_nodes_decode", input, || {
                let k = input.first().map_or(0, |b| usize::from(*b) % types.len());
                (types[k].1)(&mutate(&seeds[k], input.get(1..).unwrap_or(&[])));
            })
        });
    println!("{}", report("cdr_into_the_types_nodes_decode"));
}

/// A small real bag (the importer's example export) and its .mcap file.
fn seed_bag(dir: &Path) -> PathBuf {
    let bag = dir.join("seed_bag");
    let examples = workspace_root().join("crates/bagtools/examples");
    let mapping =
        metrocell_bagtools::import::Mapping::load(&examples.join("leica_mapping.yaml")).unwrap();
    metrocell_bagtools::import::import_csv(
        &examples.join("leica_export.csv"),
        &bag,
        Some(&mapping),
        WriterOptions::default(),
    )
    .unwrap();
    std::fs::read_dir(&bag)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "mcap"))
        .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn mcap_files() {
    let dir = scratch("mcap");
    let mcap = seed_bag(&dir);
    let seed = std::fs::read(&mcap).unwrap();
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("mcap_files", input, || {
                std::fs::write(&mcap, mutate(&seed, input)).unwrap();
                for mode in [ReadMode::Strict, ReadMode::Tolerant] {
                    if let Ok(reader) = BagReader::open_with(mcap.parent().unwrap(), mode) {
                        let _ = reader.read_all(&MessageFilter::default());
                    }
                }
            })
        });
    println!("{}", report("mcap_files"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bag_recover() {
    let dir = scratch("recover");
    let mcap = seed_bag(&dir);
    let seed = std::fs::read(&mcap).unwrap();
    let bag = mcap.parent().unwrap().to_path_buf();
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("bag_recover", input, || {
                // recovery rewrites the bag: start each run from the damaged seed
                for e in std::fs::read_dir(&bag).unwrap() {
                    let p = e.unwrap().path();
                    if p != mcap && p.file_name().is_some_and(|n| n != "metadata.yaml") {
                        let _ = std::fs::remove_file(&p);
                    }
                }
                std::fs::write(&mcap, mutate(&seed, input)).unwrap();
                let _ = metrocell_bag::recover(&bag);
            })
        });
    println!("{}", report("bag_recover"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn csv_import() {
    let dir = scratch("csv");
    let examples = workspace_root().join("crates/bagtools/examples");
    let csv_seed = std::fs::read(examples.join("leica_export.csv")).unwrap();
    let mapping_seed = std::fs::read(examples.join("leica_mapping.yaml")).unwrap();
    let (csv, mapping_file) = (dir.join("export.csv"), dir.join("mapping.yaml"));
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("csv_import", input, || {
                let (a, b) = input.split_at(input.len() / 2);
                std::fs::write(&csv, mutate(&csv_seed, a)).unwrap();
                std::fs::write(&mapping_file, mutate(&mapping_seed, b)).unwrap();
                let bag = dir.join("bag");
                let _ = std::fs::remove_dir_all(&bag);
                if let Ok(mapping) = metrocell_bagtools::import::Mapping::load(&mapping_file) {
                    let _ = metrocell_bagtools::import::import_csv(
                        &csv,
                        &bag,
                        Some(&mapping),
                        WriterOptions::default(),
                    );
                }
            })
        });
    println!("{}", report("csv_import"));
    let _ = std::fs::remove_dir_all(&dir);
}
