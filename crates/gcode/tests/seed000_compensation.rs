//! Seed 000 (photogrammetric calibration of a CNC router): eq. 7 with the B72 coefficients
//! (Table T4 of the digest) and the compensation example, plus the G-code invariants of its
//! test case T9.

use metrocell_gcode::{
    compensate_point, compensate_program, CompensationOptions, ErrorField, InverseMethod,
    PlanarQuadraticField, Region, ZeroField,
};
use nalgebra::Vector3;

fn mm(x: f64, y: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x, y, z) * 1e-3
}

#[test]
fn eq7_b72_reproduces_table_t4() {
    let f = PlanarQuadraticField::seed000_b72();
    // (X1, X2) mm → (e_x, e_y) mm, to the digits the digest prints
    let table = [
        ((0.0, 0.0), (0.00485, -0.0000112), 1e-7),
        ((100.0, 0.0), (-0.7052, 0.9550), 5e-5),
        ((0.0, 100.0), (0.6259, 1.0300), 5e-5),
        ((100.0, 100.0), (-0.0842, 1.7840), 5e-5),
        ((62.5, 62.5), (-0.0744, 1.1984), 5e-5),
        ((137.5, 137.5), (-0.0654, 2.2694), 5e-5),
    ];
    for ((x1, x2), (ex, ey), tol) in table {
        let (gx, gy) = f.error_mm(x1, x2);
        assert!(
            (gx - ex).abs() <= tol + 1e-12 && (gy - ey).abs() <= tol + 1e-12,
            "({x1}, {x2}): got ({gx}, {gy}), table ({ex}, {ey})"
        );
    }
}

#[test]
fn compensating_100_100_gives_the_papers_point_first_order_and_exact_fixed_point() {
    let f = PlanarQuadraticField::seed000_b72();
    let t = mm(100.0, 100.0, 0.0);
    let c = compensate_point(&f, &t, &[1.0; 3], InverseMethod::FirstOrder).unwrap() * 1e3;
    assert!(
        (c.x - 100.0842).abs() <= 0.5e-4 + 1e-9 && (c.y - 98.2160).abs() <= 0.5e-4 + 1e-9,
        "{c:?}"
    );
    // the fixed point makes the machine reach the target; the paper's one step does not quite
    let cf = compensate_point(&f, &t, &[1.0; 3], InverseMethod::FixedPoint).unwrap();
    let reached = cf + f.error(&cf, &[1.0; 3]).unwrap();
    assert!(
        (reached - t).norm() < 1e-12,
        "fixed point reaches {reached:?}"
    );
    let c1 = c * 1e-3;
    let miss = (c1 + f.error(&c1, &[1.0; 3]).unwrap() - t).norm();
    assert!(
        miss > 5e-6 && miss < 50e-6,
        "first order misses by {miss} m (the digest estimates ≈ |∇e|·|e| ≈ 15 µm)"
    );
}

#[test]
fn zero_model_changes_nothing_but_the_header() {
    let program = "%\nO1000 (router test)\nG21 G90 G17\nG0 X0 Y0 Z5\nG1 Z-1 F300\nX100 Y100\nG2 X150 Y50 I50 J0\nG3 X100 Y0 R50 ; back\nG91 G1 X-10 Y5\nG90\nM30\n%\n";
    let (out, report) = compensate_program(program, &ZeroField, &CompensationOptions::default());
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some("%"));
    assert!(lines.next().unwrap().starts_with("(metrocell compensate:"));
    let rest: Vec<&str> = lines.collect();
    let original: Vec<&str> = program.lines().skip(1).collect();
    assert_eq!(rest, original);
    assert_eq!(
        out.len(),
        program.len() + out.lines().nth(1).unwrap().len() + 1
    );
    assert_eq!(
        (
            report.changed_lines,
            report.added_lines,
            report.motion_lines
        ),
        (0, 0, 6)
    );
    assert!(
        report.malformed.is_empty() && report.warnings.is_empty(),
        "{report:?}"
    );
}

/// A pure offset field (only D and G): every XY shifts by (−D, −G); Z, F, S unchanged (T9).
#[test]
fn constant_offset_shifts_xy_only() {
    let f = PlanarQuadraticField {
        coefficients: [0.0, 0.0, 0.0, 0.25, 0.0, 0.0, -0.5, 0.0, 0.0],
        x3: 1.0,
        region: None,
    };
    let program = "G21 G90\nG0 X10 Y20 Z5 S12000 M3\nG1 X30 Z-2 F450\n";
    let (out, report) = compensate_program(program, &f, &CompensationOptions::default());
    let lines: Vec<&str> = out.lines().skip(1).collect();
    assert_eq!(
        lines,
        vec![
            "G21 G90",
            "G0 X9.75 Y20.5 Z5 S12000 M3",
            "G1 X29.75 Z-2 F450"
        ]
    );
    assert_eq!((report.changed_lines, report.added_lines), (2, 0));
    assert!((report.max_correction_m - (0.25f64.hypot(0.5)) * 1e-3).abs() < 1e-12);
}

/// In G91 the increments are between commanded points: the sum of the written increments is
/// the last commanded point.
#[test]
fn incremental_moves_keep_their_sum() {
    let f = PlanarQuadraticField::seed000_b72();
    let program = "G21 G91\nG1 X50 F1000\nY50\nX50\nY50\n";
    let opts = CompensationOptions {
        chord_tolerance_mm: 1.0,
        ..Default::default()
    };
    let (out, _) = compensate_program(program, &f, &opts);
    let mut sum = Vector3::zeros();
    for l in out.lines().skip(2) {
        let b = metrocell_gcode::block::parse_block(l).unwrap();
        sum += Vector3::new(
            b.value('X').unwrap_or(0.0),
            b.value('Y').unwrap_or(0.0),
            b.value('Z').unwrap_or(0.0),
        );
    }
    let expected = compensate_point(
        &f,
        &mm(100.0, 100.0, 0.0),
        &[1.0; 3],
        InverseMethod::FixedPoint,
    )
    .unwrap()
        * 1e3;
    assert!(
        (sum - expected).norm() < 2e-4,
        "written increments sum to {sum:?}, commanded end {expected:?}"
    );
}

/// A long straight move across a curved field is split so every commanded chord stays within
/// the tolerance of the compensated path; the machine then follows the programmed line.
#[test]
fn bent_lines_are_split_to_the_chord_tolerance() {
    let f = PlanarQuadraticField::seed000_b72();
    let program = "G21 G90 G0 X0 Y150\nG1 X150 Y0 F1000\n";
    let tol = 0.002;
    let opts = CompensationOptions {
        chord_tolerance_mm: tol,
        ..Default::default()
    };
    let (out, report) = compensate_program(program, &f, &opts);
    assert!(report.added_lines > 2, "{}", report.summary());
    // walk the commanded polyline; at every chord midpoint the machine's reached point must be
    // within tol (+ the field's curvature over a half chord) of the programmed diagonal x + y = 150
    let mut pts = Vec::new();
    let mut cur = Vector3::zeros();
    for l in out.lines().skip(1) {
        let b = metrocell_gcode::block::parse_block(l).unwrap();
        for (k, a) in ['X', 'Y', 'Z'].iter().enumerate() {
            if let Some(v) = b.value(*a) {
                cur[k] = v;
            }
        }
        pts.push(cur);
    }
    let line_pts = &pts[..];
    let mut worst: f64 = 0.0;
    for w in line_pts.windows(2) {
        for s in [0.25, 0.5, 0.75] {
            let c = (w[0] + (w[1] - w[0]) * s) * 1e-3;
            let reached = (c + f.error(&c, &[1.0; 3]).unwrap()) * 1e3;
            worst = worst.max(((reached.x + reached.y - 150.0) / 2f64.sqrt()).abs());
        }
    }
    assert!(
        worst < 2.0 * tol,
        "the machine leaves the programmed line by {worst} mm:\n{out}"
    );
}

#[test]
fn malformed_lines_pass_through_with_their_numbers_and_region_warns() {
    let mut f = PlanarQuadraticField::seed000_b72();
    f.region = Some(Region {
        min: mm(0.0, 0.0, f64::NEG_INFINITY),
        max: mm(150.0, 150.0, f64::INFINITY),
    });
    let program = "G21 G90 G1 X10 Y10\nG1 X#5 Y2\nG1 X(unclosed\nG1 X200 Y10\nG28 X0 Y0\n";
    let opts = CompensationOptions {
        chord_tolerance_mm: 10.0,
        ..Default::default()
    };
    let (out, report) = compensate_program(program, &f, &opts);
    let body: Vec<&str> = out.lines().skip(1).collect();
    assert_eq!(body[1], "G1 X#5 Y2");
    assert_eq!(body[2], "G1 X(unclosed");
    assert_eq!(
        report.malformed.iter().map(|i| i.line).collect::<Vec<_>>(),
        vec![2, 3]
    );
    assert_eq!(
        report
            .outside_region
            .iter()
            .map(|i| i.line)
            .collect::<Vec<_>>(),
        vec![4]
    );
    assert_eq!(
        report.warnings.iter().map(|i| i.line).collect::<Vec<_>>(),
        vec![5],
        "G28 is reported: {:?}",
        report.warnings
    );
    assert_eq!(body[4], "G28 X0 Y0");
}

#[test]
fn arcs_become_chords_that_the_machine_turns_back_into_the_arc() {
    let f = PlanarQuadraticField::seed000_b72();
    let program = "G21 G90 G17 G0 X100 Y50\nG3 X50 Y100 I-50 J0 F800\nG1 X60\n";
    let tol = 0.001;
    let (out, report) = compensate_program(
        program,
        &f,
        &CompensationOptions {
            chord_tolerance_mm: tol,
            ..Default::default()
        },
    );
    let body: Vec<&str> = out.lines().skip(1).collect();
    assert!(
        body[1].starts_with("G1 X") && !body[1].contains('I') && body[1].contains("F800"),
        "{}",
        body[1]
    );
    assert!(report.added_lines >= 10);
    // every commanded chord end, once the machine's error is added, lies on the programmed
    // circle of radius 50 about (50, 50)
    for l in &body[1..body.len() - 1] {
        let b = metrocell_gcode::block::parse_block(l).unwrap();
        let c = mm(b.value('X').unwrap(), b.value('Y').unwrap(), 0.0);
        let r = (c + f.error(&c, &[1.0; 3]).unwrap()) * 1e3;
        // 4 decimals written: the reached point is on the circle to the 0.1 µm of the output
        assert!(((r.x - 50.0).hypot(r.y - 50.0) - 50.0).abs() < 1e-4, "{l}");
    }
    // the next modal line is written out with its motion code kept (G1 was explicit there)
    assert!(body.last().unwrap().starts_with("G1 X"));
}

/// T5: the B72 field on the hypothesised 6 × 6 hole grid (pitch 25 mm, centres 12.5 … 137.5 mm)
/// predicts the paper's uncalibrated statistics: the digest's predicted figures to the digits it
/// prints, and the paper's measured ones within the loose band an [Inference]-level check
/// allows — except the mean of e_x, where the paper's −0.5 mm is what B72 does not explain
/// (consistent with its "no evident improvement of the x mean").
#[test]
fn t5_b72_on_the_hole_grid_predicts_the_uncalibrated_statistics() {
    let f = PlanarQuadraticField::seed000_b72();
    let centres: Vec<f64> = (0..6).map(|i| 12.5 + 25.0 * i as f64).collect();
    let (mut ex, mut ey, mut norm) = (Vec::new(), Vec::new(), Vec::new());
    for &x1 in &centres {
        for &x2 in &centres {
            let (gx, gy) = f.error_mm(x1, x2);
            ex.push(gx);
            ey.push(gy);
            norm.push(gx.hypot(gy));
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let sd = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    };
    let max = norm.iter().cloned().fold(f64::MIN, f64::max);
    let min = norm.iter().cloned().fold(f64::MAX, f64::min);
    // (statistic, computed, digest's prediction, its last digit, paper's measured, band)
    let rows = [
        ("mean e_y", mean(&ey), 1.376, 5e-4, 1.39, 0.05),
        ("SD e_y", sd(&ey), 0.496, 5e-4, 0.526, 0.05),
        ("SD e_x", sd(&ex), 0.423, 5e-4, 0.422, 0.05),
        ("mean |e|", mean(&norm), 1.44, 5e-3, 1.5378, 0.15),
        ("max |e|", max, 2.27, 5e-3, 2.4146, 0.2),
        ("min |e|", min, 0.26, 5e-3, 0.3427, 0.1),
    ];
    for (name, got, predicted, digit, paper, band) in rows {
        assert!(
            (got - predicted).abs() <= digit,
            "{name}: {got} vs the digest's {predicted}"
        );
        assert!(
            (got - paper).abs() <= band,
            "{name}: {got} vs the paper's {paper} ± {band}"
        );
    }
    let mean_ex = mean(&ex);
    assert!((mean_ex - -0.062).abs() <= 5e-4, "mean e_x {mean_ex}");
    assert!(
        (mean_ex - -0.5).abs() > 0.4,
        "B72 does not explain the paper's x mean"
    );
}
