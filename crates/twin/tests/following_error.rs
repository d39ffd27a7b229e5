//! `machine.servo` (crates/twin/src/following_error.rs): the twin's X and Y axes follow their
//! command through seed 004's plant and a position loop. Against the same cell without it (same
//! seed, same noise): on a steady move the axis lags by its dead band μ r N·lead / k_p; at every
//! dwell it stands within that band, and the serpentine's stops along one axis (the same speed
//! each way) are mirror images by approach — a reversal, as `backlash` models it; Z, without a
//! servo, is where it is told.

mod common;

use metrocell_twin::{Sample, SampleTruth, Simulation};

/// K8's Y axis (J 2e-4 kg·m², b 1e-3 N·m·s/rad, μ 0.1, N 50 N, r 6.4 mm) on a belt with
/// k_p = 2 N·m/rad: a band of 0.032 N·m / 2 N·m/rad × 6.4 mm = 102.4 µm.
const SERVO: &str = "
x: {inertia: 2e-4 kg m^2, damping: 1e-3 N m s/rad, friction: 0.1, normal_force: 50 N, radius: 6.4 mm, kp: 2 N m/rad}
y: {inertia: 2e-4, damping: 1e-3, friction: 0.1, normal_force: 50, radius: 0.0064, kp: 2}
";
const BAND: f64 = 102.4e-6;

#[test]
fn the_axes_lag_on_the_move_and_stop_within_the_band_mirrored_by_approach() {
    let plain = common::example_file("xfyz_shift.yaml");
    let mut servo = plain.clone();
    servo.machine.servo = Some(serde_yaml::from_str(SERVO).unwrap());
    let cell = common::validate(&servo);
    let bands = cell.servo.as_ref().unwrap().dead_bands();
    assert_eq!(bands.len(), 2);
    assert!(
        bands.iter().all(|(_, b)| (b - BAND).abs() < 1e-12),
        "{bands:?}"
    );
    let (a, b) = (
        Simulation::new(common::validate(&plain), 300.0, 3).unwrap(),
        Simulation::new(cell, 300.0, 3).unwrap(),
    );
    let program = &b.cell().program;
    let (mut dwells, mut moving) = ([0usize; 2], [0usize; 2]);
    // (approach, actual − commanded) at the stops of moves along one axis alone
    let mut stops: [Vec<(f64, f64)>; 2] = Default::default();
    for ((sa, ta), (_, tb)) in a.samples_with_truth().zip(b.samples_with_truth()) {
        let (t, d) = match (&sa, &ta, &tb) {
            (Sample::Tracker(r), SampleTruth::Tracker(x), SampleTruth::Tracker(y)) => {
                (r.t, y.displacement - x.displacement)
            }
            (
                Sample::MachineState(r),
                SampleTruth::MachineState { displacement: x },
                SampleTruth::MachineState { displacement: y },
            ) => (r.t, y - x),
            _ => continue,
        };
        assert!(d.z.abs() < 1e-15, "t = {t}: z has no servo, moved {}", d.z);
        let m = program.state_at(t);
        for k in 0..2 {
            if m.dwell_point.is_some() && m.velocity[k] == 0.0 {
                assert!(
                    d[k].abs() <= BAND + 1e-9,
                    "t = {t}, axis {k}: {} m off",
                    d[k]
                );
                // the move that ended this dwell's way in (searched back from the reading)
                let mut tau = t;
                while program.state_at(tau).velocity.iter().all(|v| *v == 0.0) && tau > t - 30.0 {
                    tau -= 0.05;
                }
                let before = program.state_at(tau);
                let alone = (0..3).all(|j| (j == k) == (before.velocity[j] != 0.0));
                if alone && m.dwell_point == program.state_at(t - 0.05).dwell_point {
                    stops[k].push((m.approach[k], d[k]));
                }
                dwells[k] += 1;
            } else if m.velocity[k] != 0.0 {
                // the lag is reached within a few of the loop's 10 ms time constants of a move's
                // start (the start's transient, the command leaving a stuck axis at once, is
                // larger); a reading 0.1 s into a steady move shows it
                let lag = -m.velocity[k].signum() * d[k];
                if program.state_at(t - 0.1).velocity[k] == m.velocity[k] {
                    assert!(
                        (lag - BAND).abs() < 0.01 * BAND,
                        "t = {t}, axis {k}: lag {lag} m"
                    );
                    moving[k] += 1;
                }
            }
        }
    }
    assert!(
        dwells.iter().all(|&n| n > 20) && moving.iter().all(|&n| n > 5),
        "{dwells:?} {moving:?}"
    );
    for (k, s) in stops.iter().enumerate() {
        // where the axis stopped after the serpentine's moves along it at the feed, the median
        // of each side (the integration's step puts a stop within ~v·dt of it)
        let median = |a: f64| -> f64 {
            let mut v: Vec<f64> = s.iter().filter(|(x, _)| *x == a).map(|(_, d)| *d).collect();
            assert!(!v.is_empty(), "axis {k}: no stop approached from {a}");
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (plus, minus) = (median(1.0), median(-1.0));
        // stops made the same way from either side are mirror images, and not at the command
        assert!(
            (plus + minus).abs() < 0.1 * BAND && plus.abs() > 0.1 * BAND,
            "axis {k}: from + {plus} m, from − {minus} m"
        );
    }
}

/// Seed 004's Z: a power screw (K6: r 4 mm, 8 mm a turn, so 8/2π mm of travel a radian) with the
/// K7 friction (μ 0.15) under the Z carriage's 50 N, k_p 40 N·m/rad: a band of
/// 0.15 × 4 mm × 50 N / 40 × 1.273 mm = 0.955 µm.
const SCREW: &str = "
z: {inertia: 5e-5 kg m^2, damping: 2e-4 N m s/rad, friction: 0.15, normal_force: 50 N, radius: 4 mm, lead: 1.2732395 mm/rad, kp: 40 N m/rad}
";

/// The five-axis table machine's Z follows its command through the screw: the machine-frame
/// displacement differs from the plain cell's along Z alone, within the band at rest, and the
/// tool point the tracker sights moves by that displacement turned by the table (its length
/// kept).
#[test]
fn a_five_axis_z_on_its_screw_follows_within_its_band() {
    let plain = common::example_file("five_axis_table.yaml");
    let mut servo = plain.clone();
    servo.machine.servo = Some(serde_yaml::from_str(SCREW).unwrap());
    let cell = common::validate(&servo);
    let band = cell.servo.as_ref().unwrap().dead_bands()[0].1;
    assert!(
        (band - 0.15 * 0.004 * 50.0 / 40.0 * 0.0012732395).abs() < 1e-15,
        "{band}"
    );
    let (a, b) = (
        Simulation::new(common::validate(&plain), 120.0, 2).unwrap(),
        Simulation::new(cell, 120.0, 2).unwrap(),
    );
    let program = &b.cell().program;
    let (mut at_rest, mut moved) = (0, 0);
    for ((sa, ta), (_, tb)) in a.samples_with_truth().zip(b.samples_with_truth()) {
        if let (Sample::Tracker(r), SampleTruth::Tracker(x), SampleTruth::Tracker(y)) =
            (&sa, &ta, &tb)
        {
            let d = y.displacement - x.displacement;
            assert!(d.x == 0.0 && d.y == 0.0, "t = {}: {d:?}", r.t);
            let sighted = y.tool_point - x.tool_point;
            assert!(
                (sighted.norm() - d.norm()).abs() < 1e-12,
                "t = {}: the tip moved {sighted:?} for {d:?}",
                r.t
            );
            let m = program.state_at(r.t);
            if m.velocity.iter().all(|v| *v == 0.0)
                && program
                    .state_at(r.t - 0.5)
                    .velocity
                    .iter()
                    .all(|v| *v == 0.0)
            {
                assert!(d.z.abs() <= band + 1e-12, "t = {}: {} m", r.t, d.z);
                at_rest += 1;
            }
            if d.z != 0.0 {
                moved += 1;
            }
        }
    }
    assert!(at_rest > 20 && moved > 20, "{at_rest} {moved}");
}

#[test]
fn a_servo_on_a_family_whose_axes_are_not_cartesian_is_refused() {
    let mut delta = common::example_file("delta_printer.yaml");
    delta.machine.servo = Some(serde_yaml::from_str(SERVO).unwrap());
    let e = metrocell_twin::Cell::from_file(&delta)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("machine.servo") && e.contains("cartesian and five-axis"),
        "{e}"
    );
}
