//! Rendering camera frames on worker threads changes nothing in the bag: the same cell and seed
//! give the same bytes with the frames rendered inline (0 threads) and on 3 workers reading
//! ahead, and the stream yields the same messages in the same order.

use std::path::{Path, PathBuf};

use metrocell_simulation::sim_time::{parse_start_time, DEFAULT_START_TIME};
use metrocell_simulation::{
    write_bag, BagOptions, CameraIntrinsics, FrameRendering, MessageConverter, MessageStream,
};
use metrocell_twin::{Cell, Simulation};

const DURATION: f64 = 60.0;

fn cell() -> Cell {
    Cell::from_path(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/quick_demo.yaml"),
    )
    .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn bags_are_byte_identical_whatever_the_render_thread_count() {
    let root = scratch("render-threads");
    let mut bags = Vec::new();
    for threads in [0, 3] {
        let dir = root.join(format!("t{threads}")).join("bag");
        let options = BagOptions {
            render_threads: threads,
            ..BagOptions::default()
        };
        let summary = write_bag(cell(), DURATION, 11, &dir, &options, |_| {}).unwrap();
        assert!(
            summary.messages_per_topic["/camera/image_raw"] >= 6,
            "{:?}",
            summary.messages_per_topic
        );
        bags.push((
            summary,
            std::fs::read(dir.join("bag_0.mcap")).unwrap(),
            std::fs::read(dir.join("metadata.yaml")).unwrap(),
        ));
    }
    let ((sa, ma, ya), (sb, mb, yb)) = (&bags[0], &bags[1]);
    assert_eq!(sa.messages_per_topic, sb.messages_per_topic);
    assert!(
        ma == mb,
        "bag_0.mcap differs: {} vs {} bytes",
        ma.len(),
        mb.len()
    );
    assert!(ya == yb, "metadata.yaml differs");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn threaded_stream_yields_the_inline_stream() {
    let cell = cell();
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let converter = MessageConverter::new(&cell, start, CameraIntrinsics::default())
        .unwrap()
        .with_frames(FrameRendering::default(), 5)
        .unwrap();
    let sim = Simulation::new(cell, DURATION, 5).unwrap();
    let inline: Vec<_> = MessageStream::new(&sim, &converter, Some(0.1)).collect();
    let threaded: Vec<_> = MessageStream::new(&sim, &converter, Some(0.1))
        .with_render_threads(2)
        .collect();
    let images = inline
        .iter()
        .filter(|m| Some(m.topic) == converter.topics.camera_image)
        .count();
    assert!(images >= 6, "{images} images");
    assert_eq!(inline.len(), threaded.len());
    for (k, (a, b)) in inline.iter().zip(&threaded).enumerate() {
        assert!(
            a == b,
            "message {k} differs (topics {} vs {})",
            a.topic,
            b.topic
        );
    }
}
