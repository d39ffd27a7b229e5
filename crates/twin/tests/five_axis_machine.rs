//! Five-axis B/C table through the twin: the seed 004 FK fixture reproduced by a cell with every
//! term zero; with terms on, the true tool point is the FK of the perturbed geometry (computed
//! here with crates/kinematics directly); pose targets are solved so the nominal tip is the pose.

mod common;

use metrocell_kinematics::five_axis::{FiveAxisGeometry, FiveAxisJoints};
use metrocell_twin::cell_file::CellFile;
use metrocell_twin::{Cell, MachineKinematics, Sample, SampleTruth, Simulation};
use nalgebra::Vector3;

fn quiet(cell: &mut Cell) {
    let t = cell.tracker.as_mut().unwrap();
    t.range_noise_constant = 0.0;
    t.range_noise_per_metre = 0.0;
    t.angular_noise = 0.0;
    t.warmup = None;
}

/// Seed 004 digest K1: reconstructed DH with d0 = 0, d1 = 228, d2 = 308, d3 = 140 mm gives the
/// tool point (308, 228, −140) mm. Here through a twin cell with B = C = 0, no offsets, no terms.
#[test]
fn seed_004_fixture_through_a_twin_cell() {
    let mut f: CellFile = common::example_file("five_axis_table.yaml");
    let fa = f.machine.five_axis.as_mut().unwrap();
    fa.d0 = common::q("0 mm");
    fa.tool_length = common::q("0 mm");
    fa.b_pivot = None;
    fa.c_offset = None;
    fa.workpiece_offset = None;
    f.program.as_mut().unwrap().poses.clear();
    f.program.as_mut().unwrap().home_joints = None;
    f.program.as_mut().unwrap().joints = vec![["308 mm", "228 mm", "-140 mm", "0 deg", "0 deg"]
        .iter()
        .map(|s| common::q(s))
        .collect()];
    f.terms.clear();
    let mut cell = common::validate(&f);
    quiet(&mut cell);
    let sim = Simulation::new(cell, 20.0, 1).unwrap();
    let expected = Vector3::new(0.308, 0.228, -0.140);
    // the same fixture through crates/kinematics alone
    let g = FiveAxisGeometry::new(0.0, 0.0);
    let fk = g
        .forward(&FiveAxisJoints {
            d1: 0.228,
            d2: 0.308,
            d3: 0.140,
            b: 0.0,
            c: 0.0,
        })
        .unwrap();
    assert!((fk.tip - expected).norm() < 1e-12);
    let (mut n_tracker, mut n_state) = (0, 0);
    for (s, t) in sim.samples_with_truth() {
        match (s, t) {
            (Sample::Tracker(s), SampleTruth::Tracker(tt)) => {
                assert!(
                    (tt.tool_point - expected).norm() < 1e-12,
                    "{:?}",
                    tt.tool_point
                );
                assert!(
                    (tt.commanded - expected).norm() < 1e-12,
                    "nominal tool point {:?}",
                    tt.commanded
                );
                // noise-free tracker: the reading is the tool point in the tracker frame
                let pose = sim.cell().tracker.as_ref().unwrap().pose;
                assert!((pose.rotation * s.point + pose.translation - expected).norm() < 1e-9);
                n_tracker += 1;
            }
            (Sample::MachineState(m), SampleTruth::MachineState { displacement }) => {
                assert_eq!(*m.names, ["x", "y", "z", "b", "c"]);
                assert_eq!(m.commanded, m.actual, "all terms zero");
                assert!(
                    (m.commanded[0] - 0.308).abs() < 1e-15
                        && (m.commanded[2] + 0.140).abs() < 1e-15
                );
                assert_eq!(displacement, Vector3::zeros());
                n_state += 1;
            }
            _ => {}
        }
    }
    assert_eq!((n_tracker, n_state), (200, 400));
}

/// tool_offset (dx, dy, dz) and squareness xy (s) on the example machine: the true tip equals the
/// FK of a geometry with tool length L − dz at X + dx − s·Y, Y + dy (the same machine, perturbed).
#[test]
fn true_tool_point_is_fk_of_the_perturbed_geometry() {
    let mut f = common::example_file("five_axis_table.yaml");
    f.terms = serde_yaml::from_str("[{id: tool_offset, params: {dx: 20 um, dy: -15 um, dz: 30 um}}, {id: squareness, options: {pair: xy}, params: {s: 200 urad}}]").unwrap();
    let mut cell = common::validate(&f);
    quiet(&mut cell);
    let MachineKinematics::FiveAxis(m) = cell.machine.kinematics.clone() else {
        panic!("not five-axis")
    };
    let (dx, dy, dz, s) = (20e-6, -15e-6, 30e-6, 200e-6);
    let mut perturbed: FiveAxisGeometry = m.geometry;
    perturbed.tool_length -= dz;
    let sim = Simulation::new(cell, 120.0, 3).unwrap();
    let (mut n, mut biggest, mut b_seen) = (0, 0.0f64, 0.0f64);
    for (_, t) in sim.samples_with_truth() {
        if let SampleTruth::Tracker(tt) = t {
            let q = &tt.joints;
            let j = FiveAxisJoints {
                d1: q[1] + dy,
                d2: q[0] + dx - s * q[1],
                d3: -q[2],
                b: q[3],
                c: q[4],
            };
            let expected = perturbed.forward(&j).unwrap().tip;
            assert!(
                (tt.tool_point - expected).norm() < 1e-12,
                "{:?} vs {expected:?}",
                tt.tool_point
            );
            let nominal = m
                .geometry
                .forward(&FiveAxisJoints {
                    d1: q[1],
                    d2: q[0],
                    d3: -q[2],
                    b: q[3],
                    c: q[4],
                })
                .unwrap()
                .tip;
            assert!((tt.commanded - nominal).norm() < 1e-12);
            biggest = biggest.max((tt.tool_point - nominal).norm());
            b_seen = b_seen.max(q[3].abs());
            n += 1;
        }
    }
    assert_eq!(n, 1200);
    assert!(
        b_seen > 0.5,
        "the program tilts the table (max |B| = {b_seen} rad)"
    );
    // s·Y at Y ≈ 0.5 m is 100 µm, plus the tool offset error
    assert!(
        biggest > 80e-6 && biggest < 200e-6,
        "largest error {biggest}"
    );
}

/// Pose targets are solved by the five-axis inverse: at every dwell, the nominal tool tip and tool
/// axis are the pose's.
#[test]
fn pose_targets_put_the_nominal_tip_on_the_pose() {
    let f = common::example_file("five_axis_table.yaml");
    let cell = common::validate(&f);
    let MachineKinematics::FiveAxis(m) = cell.machine.kinematics.clone() else {
        panic!("not five-axis")
    };
    assert_eq!(
        cell.program.points.len(),
        f.program.as_ref().unwrap().poses.len()
    );
    for (i, (q, p)) in cell
        .program
        .points
        .iter()
        .zip(&f.program.as_ref().unwrap().poses)
        .enumerate()
    {
        let pose = m
            .geometry
            .forward(&FiveAxisJoints {
                d1: q[1],
                d2: q[0],
                d3: -q[2],
                b: q[3],
                c: q[4],
            })
            .unwrap();
        let want = Vector3::new(
            p.position[0].to_si("p", "m").unwrap(),
            p.position[1].to_si("p", "m").unwrap(),
            p.position[2].to_si("p", "m").unwrap(),
        );
        assert!(
            (pose.tip - want).norm() < 1e-12,
            "pose {i}: tip {:?}",
            pose.tip
        );
        let axis = p
            .axis
            .map(|a| Vector3::new(a[0], a[1], a[2]).normalize())
            .unwrap_or_else(Vector3::z);
        assert!(
            (pose.axis - axis).norm() < 1e-7,
            "pose {i}: axis {:?}",
            pose.axis
        );
    }
}

/// A camera on the spindle rides the machine frame, which the workpiece sees turned by the
/// table: its pose in the workpiece frame is W(B, C)⁻¹·(tip + d)·mount, so the image shows the
/// machine error d in the camera's own axes whatever B and C are (W built here with
/// crates/kinematics; the nominal tip from its forward kinematics).
#[test]
fn camera_on_the_spindle_sees_the_machine_error_in_its_own_axes_at_any_b_and_c() {
    let cell = Cell::from_path(common::cell_path("five_axis_table.yaml")).unwrap();
    let MachineKinematics::FiveAxis(m) = &cell.machine.kinematics else {
        panic!("not five-axis")
    };
    let g = m.geometry;
    let mount = cell
        .camera
        .as_ref()
        .expect("the example has a camera")
        .mount;
    let sim = Simulation::new(cell, 600.0, 3).unwrap();
    let (mut frames, mut turned) = (0, 0);
    for (s, t) in sim.samples_with_truth() {
        let (
            Sample::CameraFrameRequest(r),
            SampleTruth::CameraFrameRequest {
                tool_point,
                joints: q,
                displacement: d,
            },
        ) = (s, t)
        else {
            continue;
        };
        let w = g
            .machine_from_workpiece(q[3], q[4])
            .rotation
            .to_rotation_matrix()
            .into_inner();
        let tip = g
            .forward(&FiveAxisJoints {
                d1: q[1],
                d2: q[0],
                d3: -q[2],
                b: q[3],
                c: q[4],
            })
            .unwrap()
            .tip;
        let rotation = w.transpose() * mount.rotation;
        assert!(
            (r.rotation - rotation).norm() < 1e-12
                && (r.nominal_rotation - rotation).norm() < 1e-12,
            "B = {}, C = {}",
            q[3],
            q[4]
        );
        assert!((r.nominal_position - (tip + w.transpose() * mount.translation)).norm() < 1e-12);
        assert!((r.position - (tool_point + w.transpose() * mount.translation)).norm() < 1e-12);
        // the nominal camera centre (where the plate is centred) seen from the true camera
        let seen = r.rotation.transpose() * (r.nominal_position - r.position);
        assert!(
            d.norm() > 1e-6,
            "the example's concealed terms move the tool"
        );
        assert!(
            (seen + mount.rotation.transpose() * d).norm() < 1e-12,
            "seen {seen:?}, d {d:?} at B = {}, C = {}",
            q[3],
            q[4]
        );
        frames += 1;
        if q[3].abs() > 0.1 || q[4].abs() > 0.1 {
            turned += 1;
        }
    }
    assert!(
        frames >= 7 && turned >= 3,
        "{frames} frames, {turned} with the table turned"
    );
}
