//! Thesis kinematic identity at the twin level (digest 001 §8.3 item 8): with every error zero
//! and no noise, the tracker reads X_LT = R_LT⁻¹((x + x_t, y + y_t, z + z_t) − T_LT) exactly,
//! checked against crates/kinematics' version-B chain with zero errors.

mod common;

use metrocell_kinematics::cartesian_error_chain::{tracker_point, MachineErrors};
use metrocell_twin::{Sample, SampleTruth, Simulation, TrackerStatus};

#[test]
fn zero_errors_and_noise_give_the_nominal_point_in_the_tracker_frame() {
    let mut f = common::example_file("xfyz_shift.yaml");
    f.terms.clear();
    common::quiet_tracker(&mut f);
    let t = f.sensors.tracker.as_mut().unwrap();
    let noise = t.range_noise.as_mut().unwrap();
    noise.constant = 0.0.into();
    noise.per_metre = 0.0.into();
    t.angular_noise = Some(0.0.into());
    let cell = common::validate(&f);
    let tr = cell.tracker.clone().unwrap();
    // the twin's own pose value: the exact chain and the twin share the one pose type
    let pose = tr.pose;
    let order = cell.machine.stacking().unwrap().clone();
    let tool = cell.machine.tool_offset;
    let sim = Simulation::new(cell, 1800.0, 5).unwrap();
    let mut checked = 0;
    let mut max_err: f64 = 0.0;
    for (s, truth) in sim.samples_with_truth() {
        match (s, truth) {
            (Sample::Tracker(m), SampleTruth::Tracker(tt)) => {
                assert_eq!(m.status, TrackerStatus::Ok);
                let expected = tracker_point(
                    &order,
                    &tt.commanded,
                    &tool,
                    &MachineErrors::default(),
                    &pose,
                )
                .unwrap();
                max_err = max_err.max((m.point - expected).norm());
                assert!(m.range > 0.5, "target range {}", m.range);
                checked += 1;
            }
            (Sample::MachineState(ms), _) => {
                assert_eq!(ms.commanded, ms.actual, "zero errors: actual = commanded");
            }
            _ => {}
        }
    }
    assert_eq!(checked, 18_000);
    assert!(max_err < 1e-12, "max deviation {max_err} m");
}
