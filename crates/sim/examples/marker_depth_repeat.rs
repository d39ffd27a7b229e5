//! How well a marker's measured pose repeats at each dwell of a cell, measured as the fiducial
//! node measures it (crates/vision `detect_targets` with the cell's lens and a 20 mm marker) on
//! the twin's frames (`FrameRendering::default()`), without DDS:
//!
//!   cargo run --release -p metrocell-simulation --example marker_depth_repeat -- \
//!       [cell.yaml] [noise seeds per frame] [cell seconds] [target filter, e.g. 3,7]
//!
//! Every frame the twin takes in the first `cell seconds` (default 3600) is rendered with
//! `seeds` different noise seeds (the per-frame stamp seed, as the twin draws it, offset by 1 ns
//! per seed). Per dwell (the program target the frame was taken at) and marker it prints the
//! depth (z of the marker pose, camera frame) of every frame, the spread over the frames and the
//! σ the pose covariance states, and the corners' offsets from the renderer's ground truth. The
//! default cell is the demo's (`demo_shift.yaml`, a 6-min cycle of 24 dwells).

use std::collections::BTreeMap;
use std::path::PathBuf;

use metrocell_simulation::sim_time::{parse_start_time, stamp_ns, DEFAULT_START_TIME};
use metrocell_simulation::{CameraIntrinsics, FrameRendering, MessageConverter};
use metrocell_twin::{Cell, Sample, Simulation};
use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets, PoseInputs, TargetFamily};

const MARKER_SIDE: f64 = 0.020;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cell_path = args.first().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/demo_shift.yaml")
    });
    let seeds: u64 = args.get(1).map_or(8, |s| s.parse().expect("seeds"));
    let duration: f64 = args
        .get(2)
        .map_or(3600.0, |s| s.parse().expect("cell seconds"));
    let only: Option<Vec<u32>> = args.get(3).map(|s| {
        s.split(',')
            .map(|v| v.parse().expect("target id"))
            .collect()
    });
    let cell = Cell::from_path(&cell_path).expect("cell");
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let converter = MessageConverter::new(&cell, start, CameraIntrinsics::default())
        .unwrap()
        .with_frames(FrameRendering::default(), 1)
        .unwrap();
    let renderer = converter.frames().expect("the cell has a camera");
    let camera = renderer.camera;
    let family = TargetFamily::parse("DICT_4X4_50", None, None).unwrap();
    let params = DetectorParams {
        threads: 1,
        ..Default::default()
    };
    let sim = Simulation::new(cell, duration, 1).unwrap();
    let requests: Vec<_> = sim
        .samples()
        .filter_map(|s| {
            if let Sample::CameraFrameRequest(r) = s {
                Some(r)
            } else {
                None
            }
        })
        .collect();
    // per (dwell index in the cycle, marker): depths and stated σ
    let mut table: BTreeMap<(u32, i64), (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    for (k, req) in requests.iter().enumerate() {
        let dwell = req.target_id;
        if only.as_ref().is_some_and(|o| !o.contains(&dwell)) {
            continue;
        }
        for seed in 0..seeds {
            let stamp = stamp_ns(start, req.t) + seed;
            let view = renderer.render(req, stamp).unwrap();
            let targets = detect_targets(
                &view.image,
                &family,
                &params,
                Some(PoseInputs {
                    camera: &camera,
                    marker_side: Some(MARKER_SIDE),
                    fallback_sigma_px: 0.1,
                    intrinsics_covariance: None,
                }),
            )
            .unwrap();
            for t in &targets {
                let Some(pose) = &t.pose else { continue };
                let truth = view.markers.iter().find(|m| m.id as i64 == t.id).unwrap();
                let offsets: Vec<String> = t
                    .corners
                    .iter()
                    .zip(&truth.corners)
                    .map(|(c, g)| format!("({:+.3},{:+.3})", c.x - g.x, c.y - g.y))
                    .collect();
                println!(
                    "frame {k:3} dwell {dwell:2} seed {seed} marker {} depth {:.6} mm  x {:.4} y {:.4} mm  σz {:.1} µm  corners−truth {}",
                    t.id,
                    pose.position[2] * 1e3,
                    pose.position[0] * 1e3,
                    pose.position[1] * 1e3,
                    pose.covariance[14].sqrt() * 1e6,
                    offsets.join(" ")
                );
                let e = table.entry((dwell, t.id)).or_default();
                e.0.push(pose.position[2]);
                e.1.push(pose.covariance[14].sqrt());
            }
        }
    }
    println!("\ndwell marker  frames  depth spread (max−min, std) µm   stated σz µm (median)");
    for ((dwell, id), (z, s)) in &table {
        let mean = z.iter().sum::<f64>() / z.len() as f64;
        let std = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (z.len().max(2) - 1) as f64)
            .sqrt();
        let range = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - z.iter().cloned().fold(f64::INFINITY, f64::min);
        let mut s = s.clone();
        s.sort_by(f64::total_cmp);
        println!(
            "{dwell:5} {id:6} {:7}  {:8.1} {:8.1}   {:8.1}",
            z.len(),
            range * 1e6,
            std * 1e6,
            s[s.len() / 2] * 1e6
        );
    }
}
