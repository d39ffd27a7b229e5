//! `metrocell delta fit` end to end against a printer metrocell did not simulate:
//! tests/py/delta_print.py models a Marlin delta from Marlin's own definitions (its homing, its
//! DELTA_IK, Newton on the rods for the nozzle) whose physical rod is 1 mm longer than M665 L,
//! tower A turned 0.5°, radius 0.4 mm larger and switches at uneven heights. The command must
//! recover the rod within 0.05 mm and the angle within 0.05° (and within 3 of the σ it prints),
//! the radius within 3σ, from the photographed star alone and with probed heights; its M665/M666
//! lines, loaded into that printer, must bring the printed star's bars within 0.05 mm and — with
//! probed heights — the bed within 0.05 mm; a second round (print, measure, fit with the new
//! settings) finds nothing significant left.
//!
//! Run: `cargo build -p metrocell-cli && METROCELL_PYTHON=.venv/bin/python cargo test -p metrocell-system-tests --test delta_cli -- --nocapture`

use std::path::{Path, PathBuf};
use std::time::Duration;

use system_tests::camera_recording::recorded_photos_measure_the_same;
use system_tests::{
    bin, piped, python, run, run_ok, workspace_root, write_checkerboard_photo,
    write_pinhole_camera_info,
};

/// A feature's σ per axis: 0.02 mm in one photo (0.07226 mm/px at ~0.3 px), averaged over seed
/// 002's six shots rotated 60° apart.
const SIGMA_MM: &str = "0.0082";

fn printer(args: &[&str]) -> String {
    printer_of("default", args)
}

/// `kind`: delta_print.py's DELTA_PRINTER (`default`, or `other`: errors of the other signs).
fn printer_of(kind: &str, args: &[&str]) -> String {
    let out = run(
        piped(python())
            .arg(workspace_root().join("tests/py/delta_print.py"))
            .args(args)
            .env("DELTA_PRINTER", kind),
        Duration::from_secs(300),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

fn delta_fit(dir: &Path, settings: &Path, measurements: &Path, round: u32) -> (String, PathBuf) {
    delta_fit_with(dir, settings, measurements, round, &[])
}

fn delta_fit_with(
    dir: &Path,
    settings: &Path,
    measurements: &Path,
    round: u32,
    extra: &[&str],
) -> (String, PathBuf) {
    let new = dir.join(format!("round{round}.gcode"));
    let klipper = dir.join(format!("round{round}.cfg"));
    let out = run(
        piped(bin("metrocell"))
            .args(["delta", "fit", "--firmware"])
            .arg(settings)
            .arg("--measurements")
            .arg(measurements)
            .arg("-o")
            .arg(&new)
            .arg("--klipper")
            .arg(&klipper)
            .args(extra),
        Duration::from_secs(60),
    );
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    println!("{stdout}");
    assert!(
        out.status.success(),
        "delta fit failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read_to_string(&klipper)
        .unwrap()
        .contains("[stepper_a]"));
    (stdout, new)
}

/// "  rod length (mm)   215.0000   216.0012   +1.0012   0.0034" → (physical, change, σ)
fn row(stdout: &str, label: &str) -> (f64, f64, f64) {
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with(label))
        .unwrap_or_else(|| panic!("no `{label}` row in:\n{stdout}"));
    let v: Vec<f64> = line[line.find(')').unwrap() + 1..]
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    (v[1], v[2], v[3])
}

/// "plan 0.012345" from delta_print.py check
fn checked(report: &str, what: &str) -> f64 {
    report
        .lines()
        .find_map(|l| l.strip_prefix(&format!("{what} ")))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

#[test]
fn rod_and_tower_angle_come_back_and_the_new_settings_print_true() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("m503.txt");
    // as Marlin echoes M503 (the B word is 1.1's calibration radius, not a rod trim)
    std::fs::write(
        &settings,
        "echo:  M665 L215.00 R105.60 H250.00 S200.00 B90.00 X0.00 Y0.00 Z0.00\n\
         echo:  M666 X0.00 Y0.00 Z0.00\n",
    )
    .unwrap();
    let before = printer(&["check", settings.to_str().unwrap()]);
    assert!(checked(&before, "bars") > 0.3, "{before}");
    for (seed, heights) in [(1u64, true), (2, false)] {
        let csv = dir.join(format!("star_{seed}.csv"));
        let mut args = vec![
            "print",
            settings.to_str().unwrap(),
            csv.to_str().unwrap(),
            SIGMA_MM,
        ];
        let seed_text = seed.to_string();
        args.push(&seed_text);
        if heights {
            args.extend(["--heights", "--bars"]);
        }
        printer(&args);
        let report = dir.join(format!("report_{seed}"));
        let (stdout, new) = delta_fit_with(
            &dir,
            &settings,
            &csv,
            seed as u32,
            &[
                "--tolerance",
                "0.05mm",
                "--report",
                report.to_str().unwrap(),
            ],
        );
        let page = std::fs::read_to_string(report.join("index.html")).unwrap();
        assert!(
            page.contains("plan_before") && page.contains("M665 L216.0"),
            "{page}"
        );
        assert!(
            stdout.contains("round 1: the largest error is") && stdout.contains("run round 2"),
            "{stdout}"
        );
        let (rod, _, rod_sigma) = row(&stdout, "rod length (mm)");
        assert!(
            (rod - 216.0).abs() < 0.05 && (rod - 216.0).abs() < 3.0 * rod_sigma,
            "seed {seed}: rod {rod} ± {rod_sigma}"
        );
        let (angle, _, angle_sigma) = row(&stdout, "tower angle a (°)");
        assert!(
            (angle - 0.5).abs() < 0.05 && (angle - 0.5).abs() < 3.0 * angle_sigma,
            "seed {seed}: tower A {angle} ± {angle_sigma}"
        );
        assert!(stdout.contains("held: tower angle c"), "{stdout}");
        // the radius moves printed features in plan too (the curvature of the effector's path)
        let (radius, _, radius_sigma) = row(&stdout, "radius (mm)");
        assert!(
            (radius - 106.0).abs() < 3.0 * radius_sigma,
            "seed {seed}: radius {radius} ± {radius_sigma}"
        );
        if !heights {
            assert!(
                stdout.contains("held: endstop c — no heights measured"),
                "{stdout}"
            );
        } else {
            // seed 002's single-arm rod (eq. 13 on the caliper's bars), printed beside the fit,
            // under-corrects: one arm at a time misses the other carriages' motion (digest T14)
            let single: f64 = stdout
                .lines()
                .find_map(|l| l.trim().strip_prefix("mean rod "))
                .and_then(|r| r.split_whitespace().next())
                .unwrap_or_else(|| panic!("no eq. 13 estimate in:\n{stdout}"))
                .parse()
                .unwrap();
            assert!(
                single > 215.0
                    && single < 216.0 - 0.1
                    && (rod - 216.0).abs() < (single - 216.0).abs(),
                "eq. 13 rod {single}, full fit {rod}"
            );
        }
        let after = printer(&["check", new.to_str().unwrap()]);
        println!("{after}");
        assert!(checked(&after, "bars") < 0.05, "seed {seed}: {after}");
        assert!(checked(&after, "plan") < 0.05, "seed {seed}: {after}");
        if heights {
            assert!(checked(&after, "height") < 0.05, "seed {seed}: {after}");
            // round 2: print again with the new settings and fit: nothing significant is left
            let csv2 = dir.join("star_round2.csv");
            printer(&[
                "print",
                new.to_str().unwrap(),
                csv2.to_str().unwrap(),
                SIGMA_MM,
                "11",
                "--heights",
            ]);
            let (stdout2, _) = delta_fit_with(
                &dir,
                &new,
                &csv2,
                99,
                &["--tolerance", "0.05mm", "--round", "2"],
            );
            assert!(stdout2.contains("calibrated in 2 rounds"), "{stdout2}");
            let (_, change, sigma) = row(&stdout2, "rod length (mm)");
            assert!(
                change.abs() < 3.0 * sigma,
                "round 2 rod change {change} ± {sigma}"
            );
            let (_, change, sigma) = row(&stdout2, "tower angle a (°)");
            assert!(
                change.abs() < 3.0 * sigma,
                "round 2 angle change {change} ± {sigma}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The same through a printer whose errors have the other signs and other sizes (rod 0.7 mm
/// short, radius 0.5 mm small, towers A −0.4° and B +0.25°, C's switch the highest): a fit that
/// only worked for one sign of each error would fail here. Seed 002's eq. 13 on the same bars
/// says the rod is *longer* than M665 L: the radius error scales the bars too and it puts all of
/// it on the rod — the full fit is needed, not only iteration.
#[test]
fn a_printer_with_errors_of_other_signs_and_sizes_comes_back_too() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-other-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("m503.txt");
    std::fs::write(&settings, "M665 L215 R105.6 H250\nM666 X0 Y0 Z0\n").unwrap();
    let csv = dir.join("star.csv");
    let path = |p: &Path| p.to_str().unwrap().to_string();
    printer_of(
        "other",
        &[
            "print",
            &path(&settings),
            &path(&csv),
            SIGMA_MM,
            "2",
            "--heights",
            "--bars",
        ],
    );
    let (stdout, new) = delta_fit(&dir, &settings, &csv, 1);
    for (label, truth, bound) in [
        ("rod length (mm)", 214.3, 0.05),
        ("radius (mm)", 105.1, 0.05),
        ("tower angle a (°)", -0.4, 0.05),
        ("tower angle b (°)", 0.25, 0.05),
    ] {
        let (value, _, sigma) = row(&stdout, label);
        let off = (value - truth).abs();
        assert!(
            off < bound && off < 3.0 * sigma,
            "{label}: {value} ± {sigma}, truth {truth}"
        );
    }
    let single: f64 = stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("mean rod "))
        .and_then(|r| r.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(single > 215.0, "eq. 13's rod {single} (truth 214.3)");
    let after = printer_of("other", &["check", new.to_str().unwrap()]);
    for what in ["plan", "bars", "height"] {
        assert!(checked(&after, what) < 0.05, "{after}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Seed 002 end to end on the twin, through the commands only: `delta simulate` prints the star
/// with a printer of known geometry (after the paper test a user does) and photographs it beside
/// the card with the twin's workflow camera; `delta measure` and `delta fit` recover the rod within
/// 0.05 mm, the tower angles within 0.05° and the radius, each within 3σ; the new settings, loaded
/// into the same printer (same physical flags) and printed again, are within 0.05 mm — round 2
/// says "calibrated in 2 rounds". Two printers: the (rod +1 mm, tower A +0.5°) and one
/// whose errors have other signs and sizes. The twin's levelled printer is what showed that the
/// dots' parallax needs their absolute height (`delta fit`'s paper-test assumption): holding the
/// common endstop biased the radius by 16σ.
#[test]
fn twin_printed_and_photographed_star_comes_back_through_the_commands() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-twin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("m503.txt");
    std::fs::write(&settings, "M665 L215 R105.6 H250\nM666 X0 Y0 Z0\n").unwrap();
    let metrocell = |args: &[&str]| -> String {
        run_ok(piped(bin("metrocell")).args(args), Duration::from_secs(120))
    };
    let path = |p: PathBuf| p.to_str().unwrap().to_string();
    for (name, flags, truth) in [
        ("issue", vec![], [216.0, 105.6, 0.5, 0.0]),
        (
            "other",
            vec![
                "--rod=214.3",
                "--radius=105.1",
                "--tower-angles=-0.4,0.25",
                "--switches=437.1,436.5,438.4",
            ],
            [214.3, 105.1, -0.4, 0.25],
        ),
    ] {
        let round = |firmware: &str, r: u32, flags: &[&str]| -> (String, String) {
            let sim = path(dir.join(format!("{name}_sim{r}")));
            let mut args = vec!["delta", "simulate", "--firmware", firmware, "--photos", "2"];
            let seed = (10 + r).to_string();
            args.extend(["--seed", &seed, "-o", &sim]);
            args.extend(flags);
            metrocell(&args);
            let star = path(dir.join(format!("{name}_star{r}.csv")));
            let camera = format!("{sim}/camera_info.yaml");
            let images = format!("{sim}/photo_*.png");
            metrocell(&[
                "delta", "measure", "--camera", &camera, "--images", &images, "-o", &star,
            ]);
            let new = path(dir.join(format!("{name}_new{r}.gcode")));
            let ran = format!("{sim}/m503.txt");
            let round = r.to_string();
            let out = metrocell(&[
                "delta",
                "fit",
                "--firmware",
                &ran,
                "--measurements",
                &star,
                "-o",
                &new,
                "--tolerance",
                "0.05mm",
                "--round",
                &round,
            ]);
            let printer = std::fs::read_to_string(format!("{sim}/printer.txt")).unwrap();
            let flags = printer
                .lines()
                .find_map(|l| l.strip_prefix("flags: "))
                .unwrap()
                .to_string();
            (out, format!("{new}\n{flags}"))
        };
        let (stdout, next) = round(settings.to_str().unwrap(), 1, &flags);
        assert!(
            stdout.contains("assumed: the printer was levelled by a paper test"),
            "{stdout}"
        );
        for (label, value, bound) in [
            ("rod length (mm)", truth[0], Some(0.05)),
            ("radius (mm)", truth[1], None),
            ("tower angle a (°)", truth[2], Some(0.05)),
            ("tower angle b (°)", truth[3], Some(0.05)),
        ] {
            let (got, _, sigma) = row(&stdout, label);
            let off = (got - value).abs();
            assert!(
                off < 3.0 * sigma && bound.is_none_or(|b| off < b),
                "{name}: {label} {got} ± {sigma}, truth {value}"
            );
        }
        assert!(stdout.contains("run round 2"), "{stdout}");
        let (new, flags) = next.split_once('\n').unwrap();
        let flags: Vec<&str> = flags.split_whitespace().collect();
        let (stdout2, _) = round(new, 2, &flags);
        assert!(
            stdout2.contains("calibrated in 2 rounds"),
            "{name}: {stdout2}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `delta target`'s star.gcode, read back move by move (no metrocell parser): every dot gets
/// its design's volume of filament (±15 %, what concentric lines leave) centred on its design
/// position (to 0.01 mm), the tiles' black cells come after one filament change on top of
/// their white base, and no move leaves the 81.5 mm the star spans.
#[test]
fn target_gcode_prints_every_dot_where_designed() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-gcode-{}", std::process::id()));
    let out = run_ok(
        piped(bin("metrocell"))
            .args(["delta", "target", "-o"])
            .arg(&dir),
        Duration::from_secs(30),
    );
    assert!(out.contains("1 filament change"), "{out}");
    let program = std::fs::read_to_string(dir.join("star.gcode")).unwrap();
    let dots: Vec<[f64; 2]> = std::fs::read_to_string(dir.join("dots.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').skip(1).map(|x| x.parse().unwrap()).collect();
            [v[0], v[1]]
        })
        .collect();
    assert_eq!(dots.len(), 85);
    let word = |line: &str, letter: char| -> Option<f64> {
        line.split(';')
            .next()
            .unwrap()
            .split_whitespace()
            .find_map(|w| w.strip_prefix(letter).and_then(|v| v.parse().ok()))
    };
    let (mut x, mut y, mut z, mut e) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut per_dot = vec![(0.0, 0.0, 0.0, 0.0); dots.len()]; // filament, Σlx, Σly, Σl
    let (mut changed, mut black_cells, mut furthest) = (false, 0.0, 0.0f64);
    for line in program.lines() {
        if line.starts_with("M600") {
            assert!(!changed, "one filament change");
            changed = true;
        }
        if line.starts_with("G92") {
            e = word(line, 'E').unwrap_or(e);
            continue;
        }
        if !(line.starts_with("G0") || line.starts_with("G1")) {
            continue;
        }
        let (nx, ny) = (word(line, 'X').unwrap_or(x), word(line, 'Y').unwrap_or(y));
        z = word(line, 'Z').unwrap_or(z);
        furthest = furthest.max(nx.hypot(ny));
        if let Some(ne) = word(line, 'E') {
            let l = (nx - x).hypot(ny - y);
            if ne > e && l > 0.0 {
                let mid = [(x + nx) / 2.0, (y + ny) / 2.0];
                if changed {
                    assert!((z - 0.6).abs() < 1e-9, "black cells at 0.6 mm: {line}");
                    black_cells += ne - e;
                } else if let Some(k) = (0..dots.len())
                    .find(|&k| (mid[0] - dots[k][0]).hypot(mid[1] - dots[k][1]) < 1.6)
                {
                    let d = &mut per_dot[k];
                    d.0 += ne - e;
                    d.1 += l * mid[0];
                    d.2 += l * mid[1];
                    d.3 += l;
                }
            }
            e = ne;
        }
        (x, y) = (nx, ny);
    }
    assert!(changed && black_cells > 0.0);
    assert!(furthest < 81.5, "a move {furthest} mm from the centre");
    let design = std::f64::consts::PI * 1.5f64.powi(2) * 1.0;
    for (k, d) in per_dot.iter().enumerate() {
        let volume = d.0 * std::f64::consts::PI * 1.75f64.powi(2) / 4.0;
        assert!(
            (volume / design - 1.0).abs() < 0.15,
            "dot {k}: {volume} mm³"
        );
        let c = [d.1 / d.3, d.2 / d.3];
        assert!(
            (c[0] - dots[k][0]).hypot(c[1] - dots[k][1]) < 0.01,
            "dot {k} at {c:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_input_is_named_with_what_to_do() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("m503.txt");
    std::fs::write(&settings, "M666 X0 Y0 Z0\n").unwrap();
    let csv = dir.join("m.csv");
    std::fs::write(
        &csv,
        "kind,x_mm,y_mm,z_mm,measured_x_mm,measured_y_mm,sigma_mm\nplan,0,0,0.2,1,x,0.02\n",
    )
    .unwrap();
    let fit = |settings: &Path| {
        let out = run(
            piped(bin("metrocell"))
                .args(["delta", "fit", "--firmware"])
                .arg(settings)
                .arg("--measurements")
                .arg(&csv),
            Duration::from_secs(30),
        );
        assert_eq!(out.status.code(), Some(2));
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let e = fit(&settings);
    assert!(
        e.contains("no M665 line with L") && e.contains("M503"),
        "{e}"
    );
    std::fs::write(&settings, "M665 L215 R105.6 H250\n").unwrap();
    let e = fit(&settings);
    assert!(
        e.contains("m.csv:2") && e.contains("measured_y_mm") && e.contains("`x`"),
        "{e}"
    );
    // a point no delta with these settings reaches: a table in inches, or another printer's
    let mut rows = String::from("kind,x_mm,y_mm,z_mm,measured_x_mm,measured_y_mm,sigma_mm\n");
    for k in 0..8 {
        rows.push_str(&format!(
            "plan,{},{},0.2,{},{},0.02\n",
            10 * k,
            5 * k,
            10 * k,
            5 * k
        ));
    }
    rows.push_str("plan,300,0,0.2,300,0,0.02\n");
    std::fs::write(&csv, rows).unwrap();
    let e = fit(&settings);
    assert!(
        e.contains("m.csv:10") && e.contains("outside this printer's reach"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_sigma_it_prints_covers_the_truth_at_its_stated_rate() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-cov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("m503.txt");
    std::fs::write(&settings, "M665 L215 R105.6 H250\nM666 X0 Y0 Z0\n").unwrap();
    // (label, truth): the physical printer of delta_print.py; endstops relative to tower C's
    let truth = [
        ("rod length (mm)", 216.0),
        ("radius (mm)", 106.0),
        ("tower angle a (°)", 0.5),
        ("tower angle b (°)", 0.0),
        ("endstop a (mm)", 0.3),
        ("endstop b (mm)", 0.9),
    ];
    let seeds = 100;
    let mut z: Vec<Vec<f64>> = vec![Vec::new(); truth.len()];
    let mut rod_within = 0;
    for seed in 100..100 + seeds {
        let csv = dir.join("star.csv");
        let seed_text = seed.to_string();
        printer(&[
            "print",
            settings.to_str().unwrap(),
            csv.to_str().unwrap(),
            SIGMA_MM,
            &seed_text,
        ]);
        let out = run(
            piped(bin("metrocell"))
                .args(["delta", "fit", "--firmware"])
                .arg(&settings)
                .arg("--measurements")
                .arg(&csv),
            Duration::from_secs(60),
        );
        assert!(out.status.success());
        let stdout = String::from_utf8_lossy(&out.stdout);
        for (k, (label, t)) in truth.iter().enumerate() {
            let (value, _, sigma) = row(&stdout, label);
            z[k].push((value - t) / sigma);
            if k == 0 && (value - t).abs() < 0.05 {
                rod_within += 1;
            }
        }
    }
    for (k, (label, _)) in truth.iter().enumerate() {
        let within = |n: f64| z[k].iter().filter(|v| v.abs() < n).count() as f64 / seeds as f64;
        println!(
            "{label}: within 1σ {:.2}, 2σ {:.2}, 3σ {:.2}",
            within(1.0),
            within(2.0),
            within(3.0)
        );
        // 100 seeds: the 1σ share's binomial spread is ±0.047, the 2σ share's ±0.021 (3 of them)
        assert!((0.54..=0.82).contains(&within(1.0)), "{label}: {:?}", z[k]);
        assert!(
            within(2.0) >= 0.89 && within(4.0) == 1.0,
            "{label}: {:?}",
            z[k]
        );
    }
    println!("rod within 0.05 mm of the truth in {rod_within} of {seeds} prints");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Seed 002 end to end through the commands on a photo no metrocell code drew: `delta target`
/// writes the star, tests/py/delta_photo.py has delta_print.py's printer print its dots (each
/// dot's top at the nozzle's true height) and photographs them beside a paper checkerboard card
/// with an OpenCV camera; `delta measure` finds them, `delta fit` — modelling the parallax of
/// dots the printer's z error made taller or shorter — recovers the rod within 0.05 mm and
/// tower A's angle within 0.05°, and its settings, loaded into the printer, print the star true
/// to 0.05 mm.
#[test]
fn photographed_star_gives_settings_that_print_true() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-photo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let target = dir.join("target");
    let out = run(
        piped(bin("metrocell"))
            .args(["delta", "target", "-o"])
            .arg(&target),
        Duration::from_secs(30),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let settings = dir.join("m503.txt");
    std::fs::write(&settings, "M665 L215 R105.6 H250\nM666 X0 Y0 Z0\n").unwrap();
    let photos = dir.join("photos");
    run_ok(
        piped(python())
            .arg(workspace_root().join("tests/py/delta_photo.py"))
            .arg(&settings)
            .arg(target.join("dots.csv"))
            .arg(&photos)
            .args(["1", "3"]),
        Duration::from_secs(900),
    );
    let csv = dir.join("star.csv");
    let stdout = run_ok(
        piped(bin("metrocell"))
            .args(["delta", "measure", "--camera"])
            .arg(photos.join("camera_info.yaml"))
            .arg("--images")
            .arg(photos.join("photo_*.png"))
            .arg("-o")
            .arg(&csv),
        Duration::from_secs(120),
    );
    assert!(stdout.contains("tiles [1, 2, 3]"), "{stdout}");
    // the photo taken in the cell: published by the camera node, recorded, measured from the
    // recording with the recorded camera_info — the same rows to the last digit
    recorded_photos_measure_the_same(
        "delta",
        &photos.join("photo_*.png"),
        &photos.join("camera_info.yaml"),
        88,
        1,
        &csv,
    );
    let (stdout, new) = delta_fit(&dir, &settings, &csv, 1);
    let (rod, _, rod_sigma) = row(&stdout, "rod length (mm)");
    assert!(
        (rod - 216.0).abs() < 0.05 && (rod - 216.0).abs() < 3.0 * rod_sigma,
        "rod {rod} ± {rod_sigma}"
    );
    let (angle, _, angle_sigma) = row(&stdout, "tower angle a (°)");
    assert!(
        (angle - 0.5).abs() < 0.05 && (angle - 0.5).abs() < 3.0 * angle_sigma,
        "tower A {angle} ± {angle_sigma}"
    );
    // the photo's positions fit the geometry to their stated σ or better (the σ floor of
    // 0.03 px is conservative for 3 mm dots: χ²/dof below 1 is reported, never used to narrow)
    let chi2: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("fit: χ²/dof = "))
        .and_then(|r| r.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(chi2 < 1.5, "χ²/dof {chi2}");
    let after = printer(&["check", new.to_str().unwrap()]);
    println!("{after}");
    assert!(checked(&after, "bars") < 0.05, "{after}");
    assert!(checked(&after, "plan") < 0.05, "{after}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn measure_says_what_is_missing_from_the_photo() {
    let dir = std::env::temp_dir().join(format!("metrocell-delta-nocard-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let camera = dir.join("camera_info.yaml");
    write_pinhole_camera_info(&camera, 640, 480, 500.0);
    let blank = dir.join("blank.png");
    image::GrayImage::from_pixel(640, 480, image::Luma([60]))
        .save(&blank)
        .unwrap();
    let out = run(
        piped(bin("metrocell"))
            .args(["delta", "measure", "--camera"])
            .arg(&camera)
            .arg("--images")
            .arg(&blank)
            .arg("-o")
            .arg(dir.join("star.csv")),
        Duration::from_secs(60),
    );
    assert_eq!(out.status.code(), Some(2));
    let e = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        e.contains("blank.png")
            && e.contains("no 9×6-corner checkerboard card")
            && e.contains("lay the card"),
        "{e}"
    );
    // the card, but no star: the tiles that tell its arms apart are missing
    let card_only = dir.join("card_only.png");
    write_checkerboard_photo(&card_only, (10, 7), 0.010, [-0.05, -0.035, 0.3]);
    let out = run(
        piped(bin("metrocell"))
            .args(["delta", "measure", "--camera"])
            .arg(&camera)
            .arg("--images")
            .arg(&card_only)
            .arg("-o")
            .arg(dir.join("star.csv")),
        Duration::from_secs(60),
    );
    assert_eq!(out.status.code(), Some(2));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("0 of the star's 3 tiles") && e.contains("at least 2"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
