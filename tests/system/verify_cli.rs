//! `metrocell verify plan` from outside: the thesis's 75-point mesh (seed 001 part 2, fixture
//! 15) planned, its G-code read back move by move (every point approached in + on each axis,
//! a dwell at every stop, the time each stop is reached recomputed from the moves with
//! T_v = L_T/F + T_s(n − 1)), the suggested station the best of the stations file, the launch
//! file started dry; and a station that cannot see the points refused with what to do.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use system_tests::{bin, run};

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
