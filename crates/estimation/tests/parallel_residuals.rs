//! The residuals and Jacobian of many records, evaluated in parallel chunks (one per core), are
//! bit for bit those of each record evaluated on its own, and a failing record is named by its
//! index as a sequential pass would name it. Asked for only some columns, the evaluation writes
//! those columns, bit for bit the same, and leaves the others alone. The model's sighted points,
//! kept per record, predict what the model's full evaluation does.

#[path = "common/mod.rs"]
mod common;

use common::{records, Planned, THESIS_TRACKER};
use metrocell_estimation::PointResiduals;
use metrocell_solver::Problem;
use metrocell_twin::CellModel;
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// More records than one chunk holds (1000), so a machine with two or more cores splits them.
const READINGS: usize = 2500;

#[test]
fn chunked_evaluation_equals_record_by_record() {
    let terms = common::xfyz_geometric_terms("[y, z]", "[0 m, 0.05 m, -0.15 m]");
    let text = format!("name: chunks\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {{x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}}\n  tool_offset: [0 mm, 0 mm, -150 mm]\nsensors:\n  tracker:\n    pose: {{translation: [-0.95 m, 0.3 m, 0.62 m], euler_xyz: [0 deg, 0 deg, 56 deg]}}\n    warmup: {{offset: 0 um, amplitude: 50 um, time_constant: 60 min}}\nterms:\n{terms}");
    let model =
        CellModel::from_yaml_str_in(&text, "chunks.yaml", std::path::Path::new(".")).unwrap();
    let fm = model.forward_model().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut p = fm.params();
    for (k, name) in fm.param_names().iter().enumerate() {
        if name.starts_with("positioning") || name.starts_with("angular") {
            p[k] = rng.random_range(-1e-5..1e-5);
        }
    }
    let plan: Vec<Planned> = (0..READINGS)
        .map(|k| Planned {
            q: vec![
                rng.random_range(0.0..0.8),
                rng.random_range(0.0..0.5),
                rng.random_range(0.0..0.4),
            ],
            approach: [1.0; 3],
            temperatures: vec![],
            time_on: 600.0 + k as f64,
            tool_offset_shift: None,
        })
        .collect();
    let set = records(&fm, &p, &plan, THESIS_TRACKER, Some(5));
    let all = PointResiduals::new(&fm, &set.records).unwrap();
    let (m, n) = (all.residual_count(), all.parameter_count());
    let (mut r, mut j) = (vec![0.0; m], DMatrix::zeros(m, n));
    all.residuals_and_jacobian(&p, &mut r, &mut j).unwrap();
    let mut r_only = vec![0.0; m];
    all.residuals(&p, &mut r_only).unwrap();
    let (mut r1, mut j1) = (vec![0.0; 3], DMatrix::zeros(3, n));
    for i in 0..READINGS {
        let one = PointResiduals::new(&fm, &set.records[i..i + 1]).unwrap();
        one.residuals_and_jacobian(&p, &mut r1, &mut j1).unwrap();
        assert_eq!(&r[3 * i..3 * i + 3], &r1[..], "record {i}: residuals");
        assert_eq!(
            &r_only[3 * i..3 * i + 3],
            &r1[..],
            "record {i}: residuals without the Jacobian"
        );
        assert!(j.rows(3 * i, 3) == j1, "record {i}: Jacobian rows");
    }

    // the model's sighted points are linear in its parameters, so the evaluation kept them
    // (P₀ and A per record, crates/model `linear_target`): its predictions are the model's full
    // evaluation of each record to round-off (whitened, ~1e-10 of the stated noise)
    let kin = fm.kinematic_truth(&p).unwrap();
    assert!(fm.linear_target_columns().is_some());
    for (i, rec) in set.records.iter().enumerate() {
        let full =
            metrocell_estimation::residuals::predict(&fm, &p, &kin, rec, &mut rec.signals.clone())
                .unwrap();
        let z = all.whitening_of(i) * (rec.measured - full);
        let worst = (0..3)
            .map(|k| (z[k] - r[3 * i + k]).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-8,
            "record {i}: kept prediction differs from the model's by {worst:e} σ"
        );
    }

    // only the wanted columns: the same values, the others untouched
    let wanted: Vec<bool> = (0..n).map(|k| k % 3 != 1).collect();
    let (mut r_of, mut j_of) = (vec![0.0; m], DMatrix::from_element(m, n, f64::NAN));
    all.residuals_and_jacobian_of(&p, &mut r_of, &mut j_of, &wanted)
        .unwrap();
    assert_eq!(r_of, r, "residuals of the wanted columns' evaluation");
    for k in 0..n {
        if wanted[k] {
            assert!(j_of.column(k) == j.column(k), "wanted column {k}");
        } else {
            assert!(
                j_of.column(k).iter().all(|v| v.is_nan()),
                "unwanted column {k} written"
            );
        }
    }

    // a record the model cannot predict (its commanded joints missing) is named by its index
    let mut broken = set.records.clone();
    for i in [1800, 2400] {
        broken[i].signals.axis_position = [None; 3];
    }
    let bad = PointResiduals::new(&fm, &broken).unwrap();
    let e = bad.residuals_and_jacobian(&p, &mut r, &mut j).unwrap_err();
    assert!(e.0.starts_with("record 1800 (p1800)"), "{}", e.0);
}
