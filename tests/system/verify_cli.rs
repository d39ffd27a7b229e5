//! `metrocell verify plan` from outside: the thesis's 75-point mesh (seed 001 part 2, fixture
//! 15) planned, its G-code read back move by move (every point approached in + on each axis,
//! a dwell at every stop, the time each stop is reached recomputed from the moves with
//! T_v = L_T/F + T_s(n − 1)), the suggested station the best of the stations file, the launch
//! file started dry; and a station that cannot see the points refused with what to do.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use system_tests::{bin, piped, run, run_ok};

fn plan(out: &Path, extra: &[&str]) -> std::process::Output {
    run(
        Command::new(bin("metrocell"))
            .args([
                "verify",
                "plan",
                "--x",
                "800..1200",
                "--y",
                "100..500",
                "--z",
                "200..400",
                "--step",
                "100mm",
                "-o",
            ])
            .arg(out)
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped()),
        Duration::from_secs(120),
    )
}

fn xyz(line: &str) -> [f64; 3] {
    let mut v = [f64::NAN; 3];
    for w in line.split(';').next().unwrap().split_whitespace() {
        for (k, a) in ['X', 'Y', 'Z'].iter().enumerate() {
            if let Some(n) = w.strip_prefix(*a) {
                v[k] = n.parse().unwrap();
            }
        }
    }
    v
}

#[test]
fn the_thesis_mesh_is_planned_and_its_program_reads_back() {
    let out = std::env::temp_dir().join(format!("verify_plan_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = plan(
        &out,
        &[
            "--dwell",
            "5s",
            "--feed",
            "1000mm/min",
            "--nest-every",
            "10",
        ],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    println!("{stdout}");
    // points.csv: 75 distinct points on the 100 mm grid, the nest revisited
    let csv = std::fs::read_to_string(out.join("points.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    let points: Vec<&Vec<String>> = rows.iter().filter(|r| r[1] != "nest").collect();
    assert_eq!(points.len(), 75);
    assert_eq!(
        rows.len() - points.len(),
        8,
        "nest after every 10 points and at the end"
    );
    let mut keys: Vec<(i64, i64, i64)> = points
        .iter()
        .map(|r| {
            (
                r[2].parse::<f64>().unwrap() as i64,
                r[3].parse::<f64>().unwrap() as i64,
                r[4].parse::<f64>().unwrap() as i64,
            )
        })
        .collect();
    assert!(keys.iter().all(|k| (800..=1200).contains(&k.0)
        && k.0 % 100 == 0
        && (100..=500).contains(&k.1)
        && k.1 % 100 == 0
        && [200, 300, 400].contains(&k.2)));
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), 75);
    // the program, move by move
    let g = std::fs::read_to_string(out.join("program.ngc")).unwrap();
    let lines: Vec<&str> = g.lines().filter(|l| !l.starts_with(';')).collect();
    // the machine starts at the first point (home), as points.csv's times count
    let home = [2, 3, 4].map(|k| rows[0][k].parse::<f64>().unwrap());
    let mut at = Some(home);
    let (mut path, mut stops, mut arrivals) = (0.0, 0usize, vec![]);
    let feed = 1000.0 / 60.0; // mm/s
    for (i, l) in lines.iter().enumerate() {
        if l.starts_with("G1 X") {
            let p = xyz(l);
            if let Some(a) = at {
                path +=
                    ((p[0] - a[0]).powi(2) + (p[1] - a[1]).powi(2) + (p[2] - a[2]).powi(2)).sqrt();
            }
            at = Some(p);
            if l.contains("; ") {
                // a stop: the move before it is the approach, 2 mm below on every axis
                let before = xyz(lines[i - 1]);
                for k in 0..3 {
                    assert!(
                        (p[k] - before[k] - 2.0).abs() < 1e-9,
                        "line {i}: {l} after {}",
                        lines[i - 1]
                    );
                }
                assert_eq!(lines[i + 1], "G4 P5", "a dwell after {l}");
                stops += 1;
                arrivals.push(path / feed + 5.0 * (stops - 1) as f64);
            }
        }
    }
    assert_eq!(stops, rows.len());
    for (r, t) in rows.iter().zip(&arrivals) {
        let stated: f64 = r[5].parse().unwrap();
        assert!((stated - t).abs() < 2e-3, "{}: {stated} vs {t}", r[1]);
    }
    // the suggested station is the stations file's first, which sees every point
    let st = std::fs::read_to_string(out.join("stations.csv")).unwrap();
    let first: Vec<&str> = st.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(first[5], "true");
    let sd: Vec<f64> = st
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(5) == Some("true"))
        .map(|l| l.split(',').nth(10).unwrap().parse().unwrap())
        .collect();
    assert!(sd.len() > 10);
    let held_first = first[12].split(' ').count();
    assert!(st
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(5) == Some("true"))
        .all(|l| l.split(',').nth(12).unwrap().split(' ').count() >= held_first));
    assert!(
        stdout.contains(&format!(
            "tracker at ({:.0}, {:.0}, {:.0}) mm",
            first[1].parse::<f64>().unwrap(),
            first[2].parse::<f64>().unwrap(),
            first[3].parse::<f64>().unwrap()
        )),
        "{stdout}"
    );
    // the launch file starts the tracker node and the recorder
    let dry = run(
        Command::new(bin("metrocell"))
            .args(["launch", "--dry-run"])
            .arg(out.join("verify.launch.yaml"))
            .arg("tracker_address:=10.0.0.7:5000")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped()),
        Duration::from_secs(60),
    );
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&dry.stdout),
        String::from_utf8_lossy(&dry.stderr)
    );
    assert!(dry.status.success(), "{text}");
    assert!(
        text.contains("metrocell-tracker") && text.contains("metrocell-recorder"),
        "{text}"
    );
    assert!(
        text.contains("10.0.0.7:5000") && text.contains("warmup_target:=nest"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// `--reflectors`: a pass of the same stops per reflector offset, each after a program stop whose
/// comment has the command that publishes the offset; the default model declares the nine
/// angular errors with the first offset as its tool; with an offset across the spindle and one
/// along it every angle's slope and bow is identifiable (only the constant angles, a set-up, are
/// held), with two offsets along the spindle only the yaws (about z) of Y and Z are named held —
/// a z arm does not show a turn about z.
#[test]
fn a_plan_with_the_reflector_at_three_offsets_makes_a_pass_each_and_identifies_the_angles() {
    let out = std::env::temp_dir().join(format!("verify_plan_reflectors_{}", std::process::id()));
    let o = plan(&out, &["--reflectors", "0,0,-100;150,0,-100;0,0,-250"]);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let model = std::fs::read_to_string(out.join("model.yaml")).unwrap();
    assert_eq!(model.matches("id: angular").count(), 9, "{model}");
    assert!(
        model.contains("tool_offset: [0 mm, 0 mm, -100 mm]"),
        "{model}"
    );
    let program = std::fs::read_to_string(out.join("program.ngc")).unwrap();
    assert_eq!(program.matches("\nM0 ").count(), 3);
    let dwells = program.matches("G4 P5").count();
    let stops = csv_rows(&out.join("points.csv"));
    assert_eq!(stops.len(), dwells, "a row per stop of every pass");
    assert_eq!(stops.len() % 3, 0);
    let third = &stops[2 * stops.len() / 3];
    assert_eq!((third[6].as_str(), third[9].as_str()), ("3", "-250.0000"));
    assert!(
        program.contains("point: {x: 0.15, y: 0, z: -0.1}"),
        "the second pass's offset, in metres, in its M0's command"
    );
    // the constant angles (a set-up) are always held: the line is there
    let held = text
        .lines()
        .find(|l| l.contains("not identifiable"))
        .unwrap();
    for about in ["x", "y", "z"] {
        for axis in ["x", "y", "z"] {
            assert!(
                !held.contains(&format!("angular[{axis}:{about}].c1")),
                "{held}"
            );
        }
    }
    let o = plan(&out, &["--reflectors", "0,0,-100;0,0,-250"]);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let held = text
        .lines()
        .find(|l| l.contains("not identifiable"))
        .unwrap();
    assert!(
        held.contains("angular[y:z].c1") && held.contains("angular[z:z].c1"),
        "{held}"
    );
    assert!(
        !held.contains("angular[y:x].c1") && !held.contains("angular[x:z].c1"),
        "{held}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_station_that_cannot_see_the_points_is_refused_with_what_to_do() {
    let out = std::env::temp_dir().join(format!("verify_plan_blind_{}", std::process::id()));
    let o = plan(&out, &["--station=1000,300,600"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("closer than the tracker measures") && err.contains("--station"),
        "{err}"
    );
    assert!(
        !out.join("program.ngc").exists(),
        "nothing written for a refused plan"
    );
    let o = plan(&out, &["--station=-2000,300,1200", "--acceptance", "2deg"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("off the reflector's axis") && err.contains("--acceptance"),
        "{err}"
    );
}

/// The twin's machine: the 21 geometric errors of an XFYZ machine (positioning, straightness,
/// angular about each axis with the P5 chain's Abbe levers — X carries the workpiece, its lever
/// the whole tool position; Y carries Z; Z's only the reflector's 100 mm below the spindle —
/// and the three squarenesses), values of both signs at tens of µm and µrad, then the X scale's
/// expansion with the table's temperature and the column's lagging growth. The gauge parts the
/// tracker's pose takes (offsets c0, the straightnesses' linear terms, constant rotations) are
/// zero, so the identified map and the truth share their convention.
const TRUE_TERMS: &str = "
  - {id: positioning, options: {axis: x, order: 3, travel: [800 mm, 1200 mm]}, params: {c0: 0 um, c1: -7 um, c2: -14 um, c3: 6 um}}
  - {id: straightness, options: {axis: x, direction: y, order: 3, travel: [800 mm, 1200 mm]}, params: {c0: 0 um, c1: 0 um, c2: -6.8 um, c3: 0.6 um}}
  - {id: straightness, options: {axis: x, direction: z, order: 3, travel: [800 mm, 1200 mm]}, params: {c0: 0 um, c1: 0 um, c2: -2.1 um, c3: -7.1 um}}
  - {id: angular, options: {axis: x, about: x, lever_axes: [x, y, z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [800 mm, 1200 mm]}, params: {c0: 0 urad, c1: 0.3 urad, c2: -18.5 urad}}
  - {id: angular, options: {axis: x, about: y, lever_axes: [x, y, z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [800 mm, 1200 mm]}, params: {c0: 0 urad, c1: -2.7 urad, c2: -17.2 urad}}
  - {id: angular, options: {axis: x, about: z, lever_axes: [x, y, z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [800 mm, 1200 mm]}, params: {c0: 0 urad, c1: -16.4 urad, c2: -3 urad}}
  - {id: positioning, options: {axis: y, order: 3, travel: [100 mm, 500 mm]}, params: {c0: 0 um, c1: 13.1 um, c2: -15 um, c3: -11.1 um}}
  - {id: straightness, options: {axis: y, direction: x, order: 3, travel: [100 mm, 500 mm]}, params: {c0: 0 um, c1: 0 um, c2: 2 um, c3: 7.2 um}}
  - {id: straightness, options: {axis: y, direction: z, order: 3, travel: [100 mm, 500 mm]}, params: {c0: 0 um, c1: 0 um, c2: 1.2 um, c3: -1.7 um}}
  - {id: angular, options: {axis: y, about: x, lever_axes: [z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [100 mm, 500 mm]}, params: {c0: 0 urad, c1: 19.1 urad, c2: -18.1 urad}}
  - {id: angular, options: {axis: y, about: y, lever_axes: [z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [100 mm, 500 mm]}, params: {c0: 0 urad, c1: 14.3 urad, c2: -8.4 urad}}
  - {id: angular, options: {axis: y, about: z, lever_axes: [z], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [100 mm, 500 mm]}, params: {c0: 0 urad, c1: -14.2 urad, c2: -15.3 urad}}
  - {id: positioning, options: {axis: z, order: 2, travel: [200 mm, 400 mm]}, params: {c0: 0 um, c1: -7.7 um, c2: 12.6 um}}
  - {id: straightness, options: {axis: z, direction: x, order: 2, travel: [200 mm, 400 mm]}, params: {c0: 0 um, c1: 0 um, c2: -5.1 um}}
  - {id: straightness, options: {axis: z, direction: y, order: 2, travel: [200 mm, 400 mm]}, params: {c0: 0 um, c1: 0 um, c2: 1.3 um}}
  - {id: angular, options: {axis: z, about: x, lever_axes: [], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [200 mm, 400 mm]}, params: {c0: 0 urad, c1: 5.6 urad, c2: -5.1 urad}}
  - {id: angular, options: {axis: z, about: y, lever_axes: [], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [200 mm, 400 mm]}, params: {c0: 0 urad, c1: 1.9 urad, c2: -17.5 urad}}
  - {id: angular, options: {axis: z, about: z, lever_axes: [], abbe_offset: [0 mm, 0 mm, -100 mm], order: 2, travel: [200 mm, 400 mm]}, params: {c0: 0 urad, c1: -17.6 urad, c2: -11.8 urad}}
  - {id: squareness, options: {pair: xy}, params: {s: 14.4 urad}}
  - {id: squareness, options: {pair: xz}, params: {s: -5.8 urad}}
  - {id: squareness, options: {pair: yz}, params: {s: -14.9 urad}}
  - {id: thermal_scale, options: {axis: x, sensors: [{name: x_left, position: 800 mm}, {name: x_right, position: 1200 mm}]}, params: {alpha: 11.5e-6 1/K}}
  - {id: thermal_growth, options: {sensor: column, direction: [0, 0, -1], lag: true}, params: {coefficient: 4 um/K, time_constant: 20 min}}
";

/// What a model adds to the geometric errors a plan declares: the nine angular errors at the
/// reflector's offset `abbe_mm` (a user knows where the reflector sits) over the axes' ranges
/// `travel_mm`, with the P5 chain's levers of an XFYZ machine; the X scale's expansion with the
/// temperature `scale_sensors` reads, started at a handbook α; the column's lagging growth
/// started at a guess (a growth started at exactly 0 hides its time constant from the fit: its
/// column is zero there).
fn model_additions(travel_mm: [[f64; 2]; 3], abbe_mm: [f64; 3], scale_sensors: &str) -> String {
    let lever = [("x", "[x, y, z]"), ("y", "[z]"), ("z", "[]")];
    let abbe = format!("[{} mm, {} mm, {} mm]", abbe_mm[0], abbe_mm[1], abbe_mm[2]);
    let mut terms = String::new();
    for (k, (a, l)) in lever.iter().enumerate() {
        let travel = format!("[{} mm, {} mm]", travel_mm[k][0], travel_mm[k][1]);
        for about in ["x", "y", "z"] {
            terms += &format!("  - {{id: angular, options: {{axis: {a}, about: {about}, lever_axes: {l}, abbe_offset: {abbe}, order: 2, travel: {travel}}}, params: {{c0: 0 urad, c1: 0 urad, c2: 0 urad}}}}\n");
        }
    }
    terms += &format!("  - {{id: thermal_scale, options: {{axis: x, sensors: {scale_sensors}}}, params: {{alpha: 11.5e-6 1/K}}}}\n");
    terms += "  - {id: thermal_growth, options: {sensor: column, direction: [0, 0, -1], lag: true}, params: {coefficient: 2 um/K, time_constant: 30 min}}\n";
    terms
}

/// The twin's mesh and reflector (the plan's limits; 100 mm below the spindle) and its X
/// scale's two table thermocouples.
fn twin_model_additions() -> String {
    model_additions(
        [[800.0, 1200.0], [100.0, 500.0], [200.0, 400.0]],
        [0.0, 0.0, -100.0],
        "[{name: x_left, position: 800 mm}, {name: x_right, position: 1200 mm}]",
    )
}

fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

/// A report's map (`REP/map.csv`, `points` mesh points) against the truth there (`truth` of
/// the points in m gives the errors in m), both in the report's gauge (best-fit rigid motion
/// over the mesh removed): each component's error in units of the u the report states, and the
/// mean |error| over the points in µm — what compensating with the map really leaves.
fn map_against_truth(
    rep: &Path,
    points: usize,
    truth: impl Fn(&[Vec<f64>]) -> Vec<nalgebra::Vector3<f64>>,
) -> (Vec<f64>, f64) {
    let rows = csv_rows(&rep.join("map.csv"));
    assert_eq!(rows.len(), points, "every mesh point in the map");
    let num = |r: &[String], k: usize| r[k].parse::<f64>().unwrap();
    let q: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| (1..=3).map(|k| num(r, k) * 1e-3).collect())
        .collect();
    let mut true_map = truth(&q);
    metrocell_estimation::map_gauge::remove_rigid_motion(&q, &mut true_map);
    let (mut z, mut residual) = (vec![], 0.0);
    for (r, t) in rows.iter().zip(&true_map) {
        let d = nalgebra::Vector3::from_fn(|c, _| num(r, 4 + c) - t[c] * 1e6);
        for c in 0..3 {
            z.push(d[c] / num(r, 8 + c));
        }
        residual += d.norm();
    }
    (z, residual / rows.len() as f64)
}

/// The acceptance's second point on the twin: the plan run for a full 8-hour shift by the
/// twin's machine (the 21 geometric errors, the X scale expanding and the column growing as the
/// axis motors warm the machine, its tracker warming up through the shift), recorded, and
/// reported with the model declaring all of that (without the warm-up the report says the
/// model lacks physics) — over twenty seeds the identified map at 20 °C against the truth's falls
/// within the report's Monte Carlo u at its stated rate, and the residual volumetric error the
/// report states after compensation is what compensating really leaves (on average within
/// 1.5×; single runs beyond the report's 95 % bound for one run's mean about one in twenty).
/// The plan has the length test's lines, so each page judges ISO 10360-2's 105 measurements.
#[test]
fn a_verification_of_the_twin_reports_an_uncertainty_that_covers_the_truth() {
    let dir = std::env::temp_dir().join(format!("verify_twin_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let plan_dir = dir.join("plan");
    // the thesis mesh with the length test's lines (five lengths in each of seven directions)
    let o = plan(&plan_dir, &["--dwell", "4s", "--length-test"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stops = csv_rows(&plan_dir.join("points.csv"));
    let mesh_points = stops
        .iter()
        .map(|r| r[2..5].join(","))
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let station = csv_rows(&plan_dir.join("stations.csv")).remove(0);
    let points: Vec<String> = stops
        .iter()
        .map(|r| format!("    [{} mm, {} mm, {} mm]", r[2], r[3], r[4]))
        .collect();
    let cell = format!(
        "name: verify_twin
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [800 mm, 1200 mm], y: [100 mm, 500 mm], z: [200 mm, 400 mm]}}
  tool_offset: [0 mm, 0 mm, -100 mm]
sensors:
  tracker:
    pose: {{translation: [{} mm, {} mm, {} mm], euler_xyz: [0 deg, 0 deg, {} deg]}}
    rate: 1 Hz
    range_noise: {{constant: 4 um, per_metre: 0.8 um/m}}
    angular_noise: 3 urad
    warmup: {{offset: 0 um, amplitude: 75 um, time_constant: 90 min}}
    powered_on_before_start: 20 min
  thermocouples:
    - {{name: x_left,  location: table,  noise: 0.02 K, rate: 1 Hz}}
    - {{name: x_right, location: table,  noise: 0.02 K, rate: 1 Hz}}
    - {{name: column,  location: column, noise: 0.02 K, rate: 1 Hz}}
  machine_state: {{rate: 10 Hz}}
environment:
  ambient: {{mean: 20.3 degC, drift: 0.2 K/h}}
  heat_sources:
    - name: axis_motors
      duty: [{{start: 0 h, end: 8 h, level: 1}}]
  nodes:
    - {{name: table,  time_constant: 40 min, heating: {{axis_motors: 1.5 K}}, initial: 20.3 degC}}
    - {{name: column, time_constant: 1 h,    heating: {{axis_motors: 2.5 K}}, initial: 20.3 degC}}
  thermal_step: 1 s
  air: {{pressure: 101.3 kPa, humidity: 50}}
program:
  points: [
{}
  ]
  feed_rate: 1000 mm/min
  dwell: 4 s
  cycles: 30
terms:
{TRUE_TERMS}",
        station[1],
        station[2],
        station[3],
        station[4],
        points.join(",\n")
    );
    let cell_path = dir.join("cell.yaml");
    std::fs::write(&cell_path, &cell).unwrap();
    // the model: the plan's, with the angular errors, the thermal terms and the tracker's
    // warm-up declared (the tracker was switched on 20 min before the run, the Leica curve of
    // thesis P1: 75 µm over τ = 90 min)
    let plan_model = std::fs::read_to_string(plan_dir.join("model.yaml")).unwrap();
    let full_model = plan_model.replacen(
        "euler_xyz: [0 deg, 0 deg, 0 deg]}\n",
        "euler_xyz: [0 deg, 0 deg, 0 deg]}\n    warmup: {offset: 0 um, amplitude: 50 um, time_constant: 60 min}\n",
        1,
    );
    assert_ne!(full_model, plan_model);
    let full_model = format!("{}\n{}", full_model.trim_end(), twin_model_additions());
    std::fs::write(dir.join("model.yaml"), &full_model).unwrap();
    // the model without the warm-up, for the report that must say the model lacks physics
    let cold_model = format!("{}\n{}", plan_model.trim_end(), twin_model_additions());
    std::fs::write(dir.join("cold_model.yaml"), &cold_model).unwrap();
    let truth = metrocell_twin::CellModel::from_path(&cell_path).unwrap();
    let tfm = truth.forward_model().unwrap();
    // the checks signed with the verification: a probe-tip sphere and a hole plate, from the
    // independent generators, onto the first seed's page
    let py = |args: &[&str]| {
        let o = run(
            Command::new(system_tests::python())
                .args(args)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(60),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let root = system_tests::workspace_root();
    let tip = dir.join("tip.csv");
    py(&[
        root.join("tests/py/probe_tip.py").to_str().unwrap(),
        tip.to_str().unwrap(),
        "0.0",
        "12",
    ]);
    py(&[
        root.join("tests/py/hole_plate.py").to_str().unwrap(),
        dir.join("plate").to_str().unwrap(),
    ]);
    let o = run(
        Command::new(bin("metrocell"))
            .args(["verify", "plate", "--temperature", "21.3", "--nominal"])
            .arg(dir.join("plate/nominal.csv"))
            .arg("--measured")
            .arg(dir.join("plate/z50.csv"))
            .arg("--measured")
            .arg(dir.join("plate/z250.csv"))
            .arg("--json")
            .arg(dir.join("plate.json"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped()),
        Duration::from_secs(60),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (mut z, mut actual, mut stated, mut p95) = (vec![], vec![], vec![], vec![]);
    // VERIFY_TWIN_SEEDS=N runs another number (4 seeds gave 0.50 within 1σ once: too few to judge)
    let seeds: u64 = std::env::var("VERIFY_TWIN_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    // the truth's map at 20 °C, as the report states its own
    let reference = metrocell_verification::reference_conditions::at_reference_temperature(
        &metrocell_physics::Signals {
            temperatures: ["x_left", "x_right", "column"]
                .iter()
                .map(|n| (n.to_string(), 25.0))
                .collect(),
            ..Default::default()
        },
    );
    for seed in 1..=seeds {
        let bag = dir.join(format!("bag{seed}"));
        let sim = run(
            Command::new(bin("metrocell"))
                .args([
                    "sim",
                    "--quiet",
                    "--duration",
                    "8h",
                    "--seed",
                    &seed.to_string(),
                    "--cell",
                ])
                .arg(&cell_path)
                .arg("-o")
                .arg(&bag)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(300),
        );
        assert!(
            sim.status.success(),
            "{}",
            String::from_utf8_lossy(&sim.stderr)
        );
        let rep = dir.join(format!("report{seed}"));
        let o = run(
            Command::new(bin("metrocell"))
                .args([
                    "verify", "report", "--trials", "30", "--mpe-a", "5um", "--mpe-k", "200",
                    "--mpe-b", "8um", "--model",
                ])
                .arg(dir.join("model.yaml"))
                .arg(&bag)
                .args(if seed == 1 {
                    vec![
                        "--probe-tip".to_string(),
                        tip.display().to_string(),
                        "--plate".into(),
                        dir.join("plate.json").display().to_string(),
                    ]
                } else {
                    vec![]
                })
                .arg("-o")
                .arg(&rep)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(600),
        );
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{text}\n{}",
            String::from_utf8_lossy(&o.stderr)
        );
        if seed == 1 {
            println!("{text}");
            let page = std::fs::read_to_string(rep.join("index.html")).unwrap();
            for needle in [
                "Probe-tip check",
                "three-lobe pattern",
                "Hole plate (XY)",
                "mrad (k = 1)",
                "Length test",
                "ISO/TS 15530-3",
                "bag1",
            ] {
                assert!(page.contains(needle), "the page has no {needle:?}");
            }
            assert!(!text.contains("warning: χ²/dof"), "{text}");
            // Z's angular errors (and Y's yaw) act through a lever the mesh never changes
            assert!(
                text.contains(
                    "not separable from straightness with the reflector at one tool offset"
                ),
                "{text}"
            );
            // the plan's model without the warm-up: the report says the model lacks physics
            let o = run(
                Command::new(bin("metrocell"))
                    .args(["verify", "report", "--trials", "10", "--model"])
                    .arg(dir.join("cold_model.yaml"))
                    .arg(&bag)
                    .arg("-o")
                    .arg(dir.join("cold_report"))
                    .stdout(Stdio::piped())
                    .stderr(Stdio::piped()),
                Duration::from_secs(600),
            );
            let cold = String::from_utf8_lossy(&o.stdout);
            assert!(
                o.status.success()
                    && cold.contains("warning: χ²/dof")
                    && cold.contains("lacks physics"),
                "{cold}"
            );
        }
        let (seed_z, residual) = map_against_truth(&rep, mesh_points, |q| {
            metrocell_estimation::volumetric_monte_carlo::error_map(
                &tfm,
                &tfm.params(),
                q,
                &reference,
            )
            .unwrap()
        });
        z.extend(seed_z);
        actual.push(residual);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(rep.join("verification.json")).unwrap())
                .unwrap();
        stated.push(json["residual_after_um"]["mean"].as_f64().unwrap());
        p95.push(
            json["residual_after_um"]["trial_mean_p95"]
                .as_f64()
                .unwrap(),
        );
        assert!(rep.join("index.html").exists());
        let lengths = json["length_test"].as_array().unwrap();
        // ISO 10360-2's 105: 5 lengths × 7 directions × 3 repetitions
        assert_eq!(lengths.len(), 105, "{} lengths", lengths.len());
        assert!(
            lengths.iter().all(|l| l["decision_after"].is_string()),
            "each length judged"
        );
    }
    let within = |k: f64| z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64;
    println!(
        "map error / stated u over {seeds} seeds × {mesh_points} points × 3: within 1σ {:.3}, 2σ {:.3}, 3σ {:.3}; \
         residual after compensation: actual {actual:.2?} µm, stated {stated:.2?} µm, one run's 95 % bound {p95:.2?} µm",
        within(1.0),
        within(2.0),
        within(3.0)
    );
    assert!((0.55..0.80).contains(&within(1.0)), "{}", within(1.0));
    assert!(within(2.0) > 0.9, "{}", within(2.0));
    assert!(within(3.0) > 0.98, "{}", within(3.0));
    // the residual compensation really leaves, on average over the runs, within 1.5× what
    // the reports state; single runs above their 95 % bound about one in twenty
    let n = actual.len() as f64;
    let (mean_actual, mean_stated) = (
        actual.iter().sum::<f64>() / n,
        stated.iter().sum::<f64>() / n,
    );
    assert!(
        mean_actual <= 1.5 * mean_stated,
        "actual {mean_actual} µm vs stated {mean_stated} µm"
    );
    let over = actual.iter().zip(&p95).filter(|(a, p)| a > p).count();
    assert!(
        over as f64 <= 0.05 * n + 2.0,
        "{over} of {n} runs above their 95 % bound"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Positioning and the two straightnesses of each axis as series of `orders` over the mesh's
/// ranges `travel_mm`, and the three squarenesses: what a plan declares for a mesh.
fn geometric_terms(travel_mm: [[f64; 2]; 3], orders: [usize; 3]) -> String {
    let mut terms = String::new();
    for (k, a) in ["x", "y", "z"].iter().enumerate() {
        let travel = format!("[{} mm, {} mm]", travel_mm[k][0], travel_mm[k][1]);
        let params: Vec<String> = (0..=orders[k]).map(|c| format!("c{c}: 0 um")).collect();
        let (o, p) = (orders[k], params.join(", "));
        terms += &format!("  - {{id: positioning, options: {{axis: {a}, order: {o}, travel: {travel}}}, params: {{{p}}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| *d != a) {
            terms += &format!("  - {{id: straightness, options: {{axis: {a}, direction: {d}, order: {o}, travel: {travel}}}, params: {{{p}}}}}\n");
        }
    }
    for pair in ["xy", "xz", "yz"] {
        terms +=
            &format!("  - {{id: squareness, options: {{pair: {pair}}}, params: {{s: 0 urad}}}}\n");
    }
    terms
}

/// One independent verification (bags/independent/verification_run.py, seed `seed`, 3 hours,
/// with `--reflectors` when given) in `out`, imported, with the model a user would write for it
/// (model.yaml) and its `verify report` (report/): the report's words, the truth at the mesh
/// points (m, by the point in µm) and the truth's parameters.
struct IndependentRun {
    text: String,
    truth: serde_json::Value,
    truth_at: std::collections::BTreeMap<[i64; 3], nalgebra::Vector3<f64>>,
}

fn independent_run(out: &Path, seed: u64, reflectors: Option<&str>) -> IndependentRun {
    let root = system_tests::workspace_root();
    let mut generate = piped(system_tests::python());
    generate
        .arg(root.join("bags/independent/verification_run.py"))
        .args(["--seed", &seed.to_string(), "--hours", "3", "--out"])
        .arg(out);
    if let Some(r) = reflectors {
        generate.args(["--reflectors", r]);
    }
    run_ok(&mut generate, Duration::from_secs(120));
    // what the user knows: the machine's travel, the reflector's offset, the mesh
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    let mm = |v: &serde_json::Value| v.as_f64().unwrap() * 1e3;
    let travel = &truth["travel_m"];
    let tool: Vec<f64> = (0..3).map(|k| mm(&truth["tool_offset_m"][k])).collect();
    let truth_rows = csv_rows(&out.join("truth.csv"));
    let num = |r: &[String], k: usize| r[k].parse::<f64>().unwrap();
    let mesh: [[f64; 2]; 3] = std::array::from_fn(|k| {
        let v = truth_rows.iter().map(|r| num(r, k));
        [
            v.clone().fold(f64::MAX, f64::min),
            v.fold(f64::MIN, f64::max),
        ]
    });
    let model = format!(
        "name: independent_verification
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [{} mm, {} mm], y: [{} mm, {} mm], z: [{} mm, {} mm]}}
  tool_offset: [{} mm, {} mm, {} mm]
sensors:
  tracker:
    pose: {{translation: [0 mm, 0 mm, 0 mm], euler_xyz: [0 deg, 0 deg, 0 deg]}}
    warmup: {{offset: 0 um, amplitude: 50 um, time_constant: 60 min}}
terms:
{}{}",
        mm(&travel[0][0]),
        mm(&travel[0][1]),
        mm(&travel[1][0]),
        mm(&travel[1][1]),
        mm(&travel[2][0]),
        mm(&travel[2][1]),
        tool[0],
        tool[1],
        tool[2],
        // 5 × 5 × 3 levels: cubic series on X and Y, quadratic on Z
        geometric_terms(mesh, [3, 3, 2]),
        model_additions(
            mesh,
            [tool[0], tool[1], tool[2]],
            "[{name: x_scale, position: 0 mm}]"
        )
    );
    std::fs::write(out.join("model.yaml"), model).unwrap();
    run_ok(
        piped(bin("metrocell"))
            .args(["bag", "import"])
            .arg(out.join("export.csv"))
            .arg("--mapping")
            .arg(out.join("mapping.yaml"))
            .arg("-o")
            .arg(out.join("bag")),
        Duration::from_secs(120),
    );
    let text = run_ok(
        piped(bin("metrocell"))
            .args(["verify", "report", "--trials", "20", "--model"])
            .arg(out.join("model.yaml"))
            .arg(out.join("bag"))
            .arg("-o")
            .arg(out.join("report")),
        Duration::from_secs(600),
    );
    assert!(!text.contains("warning: χ²/dof"), "seed {seed}: {text}");
    let truth_at = truth_rows
        .iter()
        .map(|r| {
            (
                std::array::from_fn(|k| (num(r, k) * 1e3).round() as i64),
                nalgebra::Vector3::from_fn(|c, _| num(r, 3 + c) * 1e-6),
            )
        })
        .collect();
    IndependentRun {
        text,
        truth,
        truth_at,
    }
}

impl IndependentRun {
    /// The report's map against the truth ([`map_against_truth`]) and the residual the report
    /// states after compensation (µm).
    fn map_scores(&self, out: &Path) -> (Vec<f64>, f64, f64) {
        let (z, residual) = map_against_truth(&out.join("report"), 75, |q| {
            q.iter()
                .map(|p| self.truth_at[&std::array::from_fn(|k| (p[k] * 1e6).round() as i64)])
                .collect()
        });
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("report/verification.json")).unwrap(),
        )
        .unwrap();
        (
            z,
            residual,
            json["residual_after_um"]["mean"].as_f64().unwrap(),
        )
    }
}

/// The fraction of `z` within ±k, for k = 1, 2, 3.
fn coverage(z: &[f64]) -> [f64; 3] {
    std::array::from_fn(|k| {
        z.iter().filter(|v| v.abs() <= (k + 1) as f64).count() as f64 / z.len() as f64
    })
}

/// The acceptance's second point on data no metrocell code made: bags/independent/
/// verification_run.py (numpy, from ISO 230-1 and -3 and from how a tracker measures) writes a
/// tracker's export of a 3-hour verification of an XFYZ machine — the 21 geometric errors with
/// the Abbe arms of the machine's own structure (reference points where a builder puts them,
/// not where the model does), the X scale expanding and the column growing as the shift warms,
/// the tracker's ADM warming up — and the truth at 20 °C. Imported with `bag import`, reported
/// with a model a user would write (the handbook α as its start), the map falls within the u
/// the report states at its stated rate over six seeds, and compensating with it leaves what the
/// report says. Before the fit judged its gauge at the nominal machine, the handbook α as the
/// start left the tracker's turn free against two straightness slopes: the map was 65 µm off.
#[test]
fn an_independent_verification_export_is_identified_within_its_stated_uncertainty() {
    let dir = std::env::temp_dir().join(format!("verify_independent_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let seeds: u64 = std::env::var("VERIFY_INDEPENDENT_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let (mut z, mut actual, mut stated) = (vec![], vec![], vec![]);
    for seed in 1..=seeds {
        let out = dir.join(format!("seed{seed}"));
        let run = independent_run(&out, seed, None);
        let (seed_z, residual, said) = run.map_scores(&out);
        z.extend(seed_z);
        actual.push(residual);
        stated.push(said);
    }
    let within = coverage(&z);
    let n = actual.len() as f64;
    let (mean_actual, mean_stated) = (
        actual.iter().sum::<f64>() / n,
        stated.iter().sum::<f64>() / n,
    );
    println!(
        "independent exports, map error / stated u over {seeds} seeds × 75 points × 3: within 1σ {:.3}, 2σ {:.3}, 3σ {:.3}; \
         residual after compensation: actual {actual:.2?} µm (mean {mean_actual:.2}), stated {stated:.2?} µm (mean {mean_stated:.2})",
        within[0], within[1], within[2]
    );
    assert!((0.55..0.85).contains(&within[0]), "{within:?}");
    assert!(within[1] > 0.9, "{within:?}");
    assert!(within[2] > 0.98, "{within:?}");
    assert!(
        mean_actual <= 1.5 * mean_stated,
        "actual {mean_actual} µm vs stated {mean_stated} µm"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The Legendre coefficients c1, c2 over the mesh's range [lo, hi] (the model's angular
/// series) of the generator's angle ε(q) = trend·(v − ½) + bow·(4v(1 − v) − ⅔), v over the
/// machine's travel [t0, t1] (bags/independent/iso_generator/geometric_errors.py): a quadratic,
/// so its values at u = −1, 0, 1 give them (P1 = u, P2 = (3u² − 1)/2).
fn legendre_c1_c2(trend: f64, bow: f64, travel: [f64; 2], mesh: [f64; 2]) -> [f64; 2] {
    let angle = |q: f64| {
        let v = (q - travel[0]) / (travel[1] - travel[0]);
        trend * (v - 0.5) + bow * (4.0 * v * (1.0 - v) - 2.0 / 3.0)
    };
    let (lo, mid, hi) = (
        angle(mesh[0]),
        angle(0.5 * (mesh[0] + mesh[1])),
        angle(mesh[1]),
    );
    [0.5 * (hi - lo), (0.5 * (hi + lo) - mid) / 1.5]
}

/// The 21 errors, all of them, on data no metrocell code made: the independent verification
/// with the reflector moved between rounds to 150 mm along X and 150 mm further down Z (ISO
/// 230-1's multi-offset verification; the export carries each reading's tool offset, `bag
/// import` writes it on /machine/tool_offset). The Abbe arms of several lengths separate the
/// nine roll, pitch and yaw errors from straightness: `calibrate` identifies every angular
/// error's slope and bow within the uncertainty it states (at its stated rate over six seeds,
/// against the generator's angles — with one reflector they are held as inseparable), and
/// `verify report` says which targets it combined and states the map for the tool, which covers
/// the truth at its stated rate.
#[test]
fn the_angular_errors_are_identified_from_a_verification_with_the_reflector_at_three_offsets() {
    let dir = std::env::temp_dir().join(format!("verify_reflectors_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let seeds: u64 = std::env::var("VERIFY_INDEPENDENT_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let (mut z_map, mut z_angular) = (vec![], vec![]);
    for seed in 1..=seeds {
        let out = dir.join(format!("seed{seed}"));
        let run = independent_run(&out, seed, Some("0,0,0;150,0,0;0,0,-150"));
        assert!(
            run.text.contains("3 targets (tool offsets")
                && !run.text.contains("not separable from straightness"),
            "seed {seed}: {}",
            run.text
        );
        z_map.extend(run.map_scores(&out).0);
        let cal = out.join("calibration.json");
        run_ok(
            piped(bin("metrocell"))
                .args(["calibrate", "--model"])
                .arg(out.join("model.yaml"))
                .arg("-o")
                .arg(out.join("calibrated.yaml"))
                .arg("--json")
                .arg(&cal)
                .arg(out.join("bag")),
            Duration::from_secs(600),
        );
        let fitted: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
        let param = |name: &str| {
            let p = fitted["parameters"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["name"] == name)
                .unwrap_or_else(|| panic!("seed {seed}: no parameter {name}"));
            (p["value"].as_f64().unwrap(), p["sigma"].as_f64())
        };
        let model = std::fs::read_to_string(out.join("model.yaml")).unwrap();
        let truth = &run.truth;
        let angular: Vec<&serde_json::Value> = truth["effects"]
            .as_array()
            .unwrap()
            .iter()
            // E_AX … E_CZ (squareness names an `about` too, but has no trend)
            .filter(|e| e["about"].is_string() && e["trend_rad"].is_number())
            .collect();
        assert_eq!(angular.len(), 9, "roll, pitch and yaw of three axes");
        for e in angular {
            let (axis, about) = (e["axis"].as_str().unwrap(), e["about"].as_str().unwrap());
            let k = ["x", "y", "z"].iter().position(|a| *a == axis).unwrap();
            let travel = [0, 1].map(|i| truth["travel_m"][k][i].as_f64().unwrap());
            // the model's range for the series: the mesh's, as the model file declares it
            let line = model
                .lines()
                .find(|l| l.contains(&format!("axis: {axis}, about: {about},")))
                .unwrap();
            let range = line.split("travel: [").nth(1).unwrap();
            let mesh: Vec<f64> = range
                .split(']')
                .next()
                .unwrap()
                .split(',')
                .map(|v| v.trim().trim_end_matches(" mm").parse::<f64>().unwrap() * 1e-3)
                .collect();
            let mut c = legendre_c1_c2(
                e["trend_rad"].as_f64().unwrap(),
                e["bow_rad"].as_f64().unwrap(),
                travel,
                [mesh[0], mesh[1]],
            );
            // the table carries the workpiece: the tool relative to it turns the other way
            if e["side"] == "workpiece" {
                c = c.map(|v| -v);
            }
            for (i, truth_c) in c.iter().enumerate() {
                let name = format!("angular[{axis}:{about}].c{}", i + 1);
                let (value, sigma) = param(&name);
                let sigma = sigma.unwrap_or_else(|| panic!("seed {seed}: {name} has no σ"));
                z_angular.push((value - truth_c) / sigma);
            }
        }
    }
    let (map, angular) = (coverage(&z_map), coverage(&z_angular));
    println!(
        "three reflectors, {seeds} seeds: angular coefficients' error / stated σ ({} values) within 1σ {:.3}, 2σ {:.3}, 3σ {:.3}; \
         map error / stated u within 1σ {:.3}, 2σ {:.3}, 3σ {:.3}",
        z_angular.len(),
        angular[0], angular[1], angular[2], map[0], map[1], map[2]
    );
    assert!((0.55..0.88).contains(&angular[0]), "{angular:?}");
    assert!(angular[1] > 0.88, "{angular:?}");
    assert!(angular[2] > 0.97, "{angular:?}");
    assert!((0.55..0.85).contains(&map[0]), "{map:?}");
    assert!(map[1] > 0.9, "{map:?}");
    assert!(map[2] > 0.98, "{map:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad input the report refuses with what to do: a model whose thermal term needs a temperature
/// the recording lacks, a plate result that is not one, and a bag that is not there.
#[test]
fn a_report_refuses_a_bag_without_the_temperatures_its_model_needs() {
    let dir = std::env::temp_dir().join(format!("verify_refuse_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cell = format!(
        "name: refuse
machine: {{family: cartesian, stacking: XFYZ, travel: {{x: [0 mm, 400 mm], y: [0 mm, 400 mm], z: [0 mm, 400 mm]}}}}
sensors:
  tracker:
    pose: {{translation: [-1200 mm, 200 mm, 600 mm], euler_xyz: [0 deg, 0 deg, 0 deg]}}
    rate: 2 Hz
    range_noise: {{constant: 4 um, per_metre: 0.8 um/m}}
    angular_noise: 3 urad
  machine_state: {{rate: 10 Hz}}
environment:
  ambient: {{mean: 20 degC}}
  air: {{pressure: 101.3 kPa, humidity: 50}}
program:
  points: [[0 mm, 0 mm, 0 mm], [400 mm, 0 mm, 0 mm], [400 mm, 400 mm, 0 mm], [0 mm, 400 mm, 200 mm]]
  feed_rate: 50 mm/s
  dwell: 3 s
terms:
{}",
        // the machine's geometry only: this cell has no thermocouples
        TRUE_TERMS
            .lines()
            .filter(|l| !l.contains("thermal"))
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    )
    .replace("800 mm, 1200 mm", "0 mm, 400 mm")
    .replace("100 mm, 500 mm", "0 mm, 400 mm")
    .replace("200 mm, 400 mm", "0 mm, 400 mm");
    std::fs::write(dir.join("cell.yaml"), &cell).unwrap();
    let bag = dir.join("bag");
    let sim = run(
        Command::new(bin("metrocell"))
            .args(["sim", "--quiet", "--duration", "2min", "--cell"])
            .arg(dir.join("cell.yaml"))
            .arg("-o")
            .arg(&bag)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped()),
        Duration::from_secs(120),
    );
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    let model = format!(
        "{cell}  - {{id: thermal_scale, options: {{axis: x, sensors: [{{name: x_left, position: 0 m}}, {{name: x_right, position: 0.4 m}}]}}, params: {{alpha: 11.5e-6 1/K}}}}\n"
    );
    std::fs::write(dir.join("model.yaml"), model).unwrap();
    let report = |bag: &Path| {
        run(
            Command::new(bin("metrocell"))
                .args(["verify", "report", "--trials", "10", "--model"])
                .arg(dir.join("model.yaml"))
                .arg(bag)
                .arg("-o")
                .arg(dir.join("report"))
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(120),
        )
    };
    let o = report(&bag);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("temperature[x_left]") && err.contains("record /temperature/x_left"),
        "{err}"
    );
    // a plate result that is not `verify plate --json`'s: refused before anything is written
    std::fs::write(dir.join("plate.json"), "{\"squareness\": 1}").unwrap();
    let o = run(
        Command::new(bin("metrocell"))
            .args(["verify", "report", "--trials", "10", "--model"])
            .arg(dir.join("cell.yaml"))
            .arg(&bag)
            .arg("--plate")
            .arg(dir.join("plate.json"))
            .arg("-o")
            .arg(dir.join("report"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped()),
        Duration::from_secs(120),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("plate.json") && err.contains("verify plate --json"),
        "{err}"
    );
    let o = report(&dir.join("no_such_bag"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no bag at") && err.contains("no_such_bag"),
        "{err}"
    );
    assert!(!dir.join("report").join("index.html").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The plate-based squareness on plates no metrocell code made (tests/py/hole_plate.py: the
/// machine's axes as direction vectors, the plate askew and warm, four probe points a ring):
/// the thesis's xWy and one of the other sign and twice the size, each within 3σ in mrad,
/// and most of the plane's error compensated by the six components (the thesis: 94.39 %).
#[test]
fn plate_squareness_from_an_independent_generator_in_the_thesis_units() {
    for (xwy, seed) in [(0.20448, 1), (-0.5, 3)] {
        let dir = std::env::temp_dir().join(format!("verify_plate_{}_{seed}", std::process::id()));
        let gen = run(
            Command::new(system_tests::python())
                .arg(system_tests::workspace_root().join("tests/py/hole_plate.py"))
                .arg(&dir)
                .arg(xwy.to_string())
                .arg(seed.to_string())
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(60),
        );
        assert!(
            gen.status.success(),
            "{}",
            String::from_utf8_lossy(&gen.stderr)
        );
        let o = run(
            Command::new(bin("metrocell"))
                .args(["verify", "plate", "--nominal"])
                .arg(dir.join("nominal.csv"))
                .arg("--measured")
                .arg(format!("{}@21.3", dir.join("z50.csv").display()))
                .arg("--measured")
                .arg(format!("{}@21.3", dir.join("z250.csv").display()))
                .arg("--json")
                .arg(dir.join("plate.json"))
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(60),
        );
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        println!("{text}");
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("plate.json")).unwrap())
                .unwrap();
        let (v, s) = (
            j["squareness_mrad"]["value"].as_f64().unwrap(),
            j["squareness_mrad"]["sigma"].as_f64().unwrap(),
        );
        assert!((v - xwy).abs() < 3.0 * s, "xWy {v} ± {s} mrad vs {xwy}");
        assert!(s < 0.02, "σ {s} mrad");
        let pct = j["compensated_percent"].as_f64().unwrap();
        assert!((85.0..99.5).contains(&pct), "{pct} %");
        std::fs::copy(
            dir.join("plate.json"),
            std::env::temp_dir().join(format!("verify_plate_{}_{seed}.json", std::process::id())),
        )
        .unwrap();
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The probe-tip check on spheres no metrocell code probed (tests/py/probe_tip.py): a tip
/// 0.3 mm off the axis with 10 µm lobes (the thesis's Table 5.3 situation: range ≈ 0.6 mm,
/// repeatability/range ≈ 1.45), and a corrected tip with 12 µm lobes (Table 5.4: lobes only).
#[test]
fn the_probe_tip_check_tells_a_bent_tip_from_the_seatings_lobes() {
    let line = |text: &str, start: &str| -> Vec<f64> {
        let l = text
            .lines()
            .find(|l| l.trim_start().starts_with(start))
            .unwrap_or_else(|| panic!("{start}: {text}"));
        l.split(|c: char| !(c.is_ascii_digit() || c == '.'))
            .filter(|t| !t.is_empty() && t.contains(|c: char| c.is_ascii_digit()))
            .filter_map(|t| t.parse().ok())
            .collect()
    };
    for (ecc_mm, lobe_um, seed) in [(0.3, 10.0, 1), (0.0, 12.0, 2)] {
        let csv = std::env::temp_dir().join(format!("probe_tip_{}_{seed}.csv", std::process::id()));
        let gen = run(
            Command::new(system_tests::python())
                .arg(system_tests::workspace_root().join("tests/py/probe_tip.py"))
                .arg(&csv)
                .arg(ecc_mm.to_string())
                .arg(lobe_um.to_string())
                .arg(seed.to_string())
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(60),
        );
        assert!(
            gen.status.success(),
            "{}",
            String::from_utf8_lossy(&gen.stderr)
        );
        let o = run(
            Command::new(bin("metrocell"))
                .args(["verify", "probe-tip"])
                .arg(&csv)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped()),
            Duration::from_secs(60),
        );
        let text = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(
            o.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        println!("{text}");
        let ecc = line(&text, "tip eccentricity");
        let lobes = line(&text, "three-lobe");
        // "tip eccentricity (once per turn): A ± σ µm" → [A, σ]; "three-lobe pattern (3 per turn, 120° apart): A ± σ µm" → [3, 120, A, σ]
        let (a1, s1) = (ecc[0], ecc[1]);
        let (a3, s3) = (lobes[2], lobes[3]);
        assert!(
            (a1 - ecc_mm * 1e3).abs() < 4.0 * s1 + 0.5,
            "eccentricity {a1} ± {s1} µm vs {ecc_mm} mm"
        );
        assert!(
            (a3 - lobe_um).abs() < 4.0 * s3,
            "lobes {a3} ± {s3} µm vs {lobe_um}"
        );
        let bent = text.contains("the tip is off the spindle axis");
        assert_eq!(bent, ecc_mm > 0.0, "{text}");
        assert!(text.contains("kinematic seating"), "{text}");
        if ecc_mm > 0.0 {
            let x = line(&text, "X ");
            assert!(
                (x[1] / x[0] - 1.45).abs() < 0.1,
                "repeatability/range {x:?} (the thesis's 1.45)"
            );
        }
        let _ = std::fs::remove_file(&csv);
    }
}
