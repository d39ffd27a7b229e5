//! Same file + seed → identical stream; another seed → different noise, same ground truth.

mod common;

use metrocell_twin::{Cell, Sample, Simulation};

fn stream(seed: u64) -> Vec<String> {
    let cell = Cell::from_path(common::cell_path("quick_demo.yaml")).unwrap();
    let sim = Simulation::new(cell, 180.0, seed).unwrap();
    // Debug text compares NaN fields of dropped samples as equal, unlike f64 ==.
    sim.samples().map(|s| format!("{s:?}")).collect()
}

#[test]
fn same_seed_gives_identical_stream() {
    let a = stream(42);
    let b = stream(42);
    assert!(a.len() > 5000, "only {} samples", a.len());
    assert_eq!(a, b);
}

#[test]
fn different_seed_gives_different_noise() {
    let a = stream(42);
    let b = stream(43);
    assert_eq!(a.len(), b.len(), "the schedule does not depend on the seed");
    let differing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    // every noisy sample differs; machine states (no noise) and thermal truths are seed-free
    assert!(
        differing > a.len() / 3,
        "only {differing} of {} samples differ",
        a.len()
    );
}

#[test]
fn stream_is_time_ordered_and_restartable() {
    let cell = Cell::from_path(common::cell_path("quick_demo.yaml")).unwrap();
    let sim = Simulation::new(cell, 180.0, 7).unwrap();
    let ts: Vec<f64> = sim.samples().map(|s| s.t()).collect();
    assert!(ts.windows(2).all(|w| w[1] >= w[0]), "not time ordered");
    assert!(*ts.last().unwrap() < 180.0);
    let kinds = |s: &Sample| match s {
        Sample::Tracker(_) => 0,
        Sample::Temperature(_) => 1,
        Sample::MachineState(_) => 2,
        Sample::ProbeHit(_) => 3,
        Sample::CameraFrameRequest(_) => 4,
        Sample::StationPoint(_) | Sample::Acceleration(_) => {
            panic!("no stationing program in this cell")
        }
    };
    let mut count = [0usize; 5];
    for s in sim.samples() {
        count[kinds(&s)] += 1;
    }
    // 180 s: tracker 10 Hz, 2 thermocouples 1 Hz, machine state 20 Hz
    assert_eq!(count[0], 1800);
    assert_eq!(count[1], 360);
    assert_eq!(count[2], 3600);
    // 6 points per 30 s cycle, 6 cycles, 4 probe directions (0.4 s apart within a 2 s dwell)
    assert_eq!(count[3], 6 * 6 * 4);
    assert_eq!(count[4], 6 * 6);
}

/// The demo's camera (crates/twin/examples/cells/demo_shift.yaml) only adds frame requests: every
/// other sample — the tracker's readings the demo's diagnosis judges, the temperatures, the
/// machine states — is the same with and without it, so adding the camera cannot change what
/// the demo finds (frame requests draw nothing from the noise streams).
#[test]
fn a_camera_adds_frames_and_changes_no_other_sample() {
    let with_camera = Cell::from_path(common::cell_path("demo_shift.yaml")).unwrap();
    assert!(
        with_camera.camera.is_some(),
        "demo_shift.yaml has a tool camera"
    );
    let mut without = Cell::from_path(common::cell_path("demo_shift.yaml")).unwrap();
    without.camera = None;
    // 30 min: five 6-min cycles of 24 dwells
    let run = |cell: Cell| {
        Simulation::new(cell, 1800.0, 1)
            .unwrap()
            .samples()
            .collect::<Vec<Sample>>()
    };
    let (a, b) = (run(with_camera), run(without));
    let frames = a
        .iter()
        .filter(|s| matches!(s, Sample::CameraFrameRequest(_)))
        .count();
    assert_eq!(frames, 5 * 24, "a frame per dwell");
    let others: Vec<String> = a
        .iter()
        .filter(|s| !matches!(s, Sample::CameraFrameRequest(_)))
        .map(|s| format!("{s:?}"))
        .collect();
    let b: Vec<String> = b.iter().map(|s| format!("{s:?}")).collect();
    // tracker 4 Hz, machine state 4 Hz, three thermocouples 1 Hz
    assert_eq!(b.len(), 1800 * (4 + 4 + 3));
    assert_eq!(others, b);
}
