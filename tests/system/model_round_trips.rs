//! Issue 32: every model file metrocell writes is read back by every command that reads a model.
//!
//! The matrix: every example cell a user would pass to `calibrate` / `diagnose` as a model
//! (crates/twin/examples/cells/*.yaml and launch-configs/cells/*.yaml; a launch-configs file
//! identical to the example of its name is the same model and runs once), as written (flow
//! style, comments) and in block style (a YAML emitter's output: serde_yaml, as Python's
//! `yaml.safe_dump(…, default_flow_style=False)` writes it), goes through `calibrate -o` and
//! `diagnose --report` on a short recording `metrocell sim` makes, and both outputs through
//! `calibrate`, `diagnose`, `compensate gcode` and `compensate table` (temperatures and their
//! history from the recording, and a steady state at given temperatures, which the output must
//! state when the model has a lagged term), `sim` and the estimator node (`--bag`, over the
//! tracker node's measured points merged with the recording).
//!
//! Which cell records the model's recording: the cell itself, except
//! * `demo_model.yaml`, the model `metrocell demo` judges `demo_shift.yaml`'s recording against
//!   (its diagnosis adds a tracker warm-up, a lagged growth and backlash: the augmented model
//!   of issue 32 item 1);
//! * `delta_printer.yaml`, measured by a camera only (nothing a sim bag holds for calibrate
//!   without rendered frames): recorded by the same delta with a tracker added;
//! * `mobile_manipulator_model.yaml`, the declared model of `mobile_manipulator.yaml` (a
//!   stationing program, recorded over its one pass; its URDF copied beside every file).
//!
//! A stationing cell simulates without a tracker pose (its instrument's setups are its own); a
//! model file without `environment` and `program` is refused by `sim`, naming them.
//!
//! What each family can do: G-code and controller tables are for X Y Z programs (cartesian,
//! delta); a five-axis or arm model is refused with a message saying so. The tracker node makes
//! measured points for cartesian and delta machines, a stationing program records its own; the
//! estimator node on another five-axis or arm recording accepts the model and names the missing
//! /measured_points.
//! A model whose output gained a tracker without a pose (diagnose found a warm-up the model
//! had no tracker for) is refused by `sim`, naming `sensors.tracker.pose`; every other output
//! simulates.
//!
//! Run: `cargo build --workspace --bins && cargo test -p metrocell-system-tests --test model_round_trips`
//! (no DDS: the nodes run on bags).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use metrocell_physics::SignalKind;
use metrocell_twin::CellModel;
use system_tests::{bin, workspace_root, ChildGuard};

/// One row of the matrix: a model file and the cell whose simulation is its recording.
struct Row {
    name: String,
    model: String,
    recorded_cell: String,
    duration: &'static str,
}

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "metrocell-model-round-trips-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A YAML file in block style, as an emitter writes it (no flow collections, no comments).
fn block_style(text: &str) -> String {
    let v: serde_yaml::Value = serde_yaml::from_str(text).unwrap();
    let out = serde_yaml::to_string(&v).unwrap();
    assert!(
        !out.contains(": [") && !out.contains(": {"),
        "not block style:\n{out}"
    );
    out
}

/// The delta example with a tracker, so its recording has points calibrate reads.
fn delta_with_tracker(text: &str) -> String {
    let tracker = "sensors:\n  tracker:\n    pose: {translation: [-700 mm, 100 mm, 300 mm], euler_xyz: [0 deg, 0 deg, 10 deg]}\n    rate: 10 Hz\n    range_noise: {constant: 4 um, per_metre: 0.8 um/m}\n    angular_noise: 3 urad\n";
    assert_eq!(text.matches("\nsensors:\n").count(), 1);
    text.replacen("\nsensors:\n", &format!("\n{tracker}"), 1)
}

fn rows() -> Vec<Row> {
    let root = workspace_root();
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in ["crates/twin/examples/cells", "launch-configs/cells"] {
        let mut here: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
            .collect();
        here.sort();
        files.extend(here);
    }
    let mut seen: Vec<String> = Vec::new();
    let mut rows = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        if seen.contains(&text) {
            continue;
        }
        seen.push(text.clone());
        let file = path.file_name().unwrap().to_string_lossy().to_string();
        let name = path.strip_prefix(&root).unwrap().display().to_string();
        let sibling = |n: &str| std::fs::read_to_string(path.with_file_name(n)).unwrap();
        // recordings as short as leave each fit something to do (demo_model's 20 min show the
        // tracker's warm-up, which its diagnosis adds)
        let (recorded_cell, duration) = match file.as_str() {
            "demo_model.yaml" => (sibling("demo_shift.yaml"), "20min"),
            "delta_printer.yaml" => (delta_with_tracker(&text), "3min"),
            "demo_shift.yaml" => (text.clone(), "5min"),
            "mobile_manipulator_model.yaml" => (sibling("mobile_manipulator.yaml"), "1h"),
            "mobile_manipulator.yaml" => (text.clone(), "1h"),
            _ => (text.clone(), "3min"),
        };
        rows.push(Row {
            name,
            model: text,
            recorded_cell,
            duration,
        });
    }
    rows
}

/// A command's exit code, stdout and stderr (output to files, so a chatty process cannot fill
/// a pipe while it is waited for).
fn run(dir: &Path, program: &str, args: &[&str]) -> (i32, String, String) {
    let (out, err) = (dir.join(".stdout"), dir.join(".stderr"));
    let mut cmd = Command::new(bin(program));
    cmd.args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap());
    let mut child = ChildGuard::spawn(&mut cmd);
    let deadline = Instant::now() + Duration::from_secs(180);
    let status = loop {
        if let Some(s) = child.child().try_wait().unwrap() {
            break s;
        }
        assert!(
            Instant::now() < deadline,
            "{program} {args:?} in {} did not finish in 180 s",
            dir.display()
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    (
        status.code().unwrap_or(-1),
        std::fs::read_to_string(out).unwrap_or_default(),
        std::fs::read_to_string(err).unwrap_or_default(),
    )
}

/// Run, and require exit code 0.
fn ok(dir: &Path, what: &str, program: &str, args: &[&str]) -> (String, String) {
    let (code, out, err) = run(dir, program, args);
    assert_eq!(
        code,
        0,
        "{what}: {program} {}\nstdout:\n{out}\nstderr:\n{err}",
        args.join(" ")
    );
    assert!(!err.contains("panicked"), "{what}: {err}");
    (out, err)
}

/// A three-point X Y Z program inside the travel (mm).
fn part_program(travel: &[[f64; 2]; 3]) -> String {
    let at = |f: f64| -> Vec<String> {
        travel
            .iter()
            .map(|t| format!("{:.3}", (t[0] + f * (t[1] - t[0])) * 1e3))
            .collect()
    };
    let mut s = String::from("G21 G90\n");
    for (k, f) in [0.25, 0.5, 0.75].into_iter().enumerate() {
        let p = at(f);
        s += &format!(
            "G1 X{} Y{} Z{}{}\n",
            p[0],
            p[1],
            p[2],
            if k == 0 { " F1000" } else { "" }
        );
    }
    s
}

/// Whether a term of the model reads temperature sensor `name` (now or its history).
fn reads(model: &CellModel, name: &str) -> bool {
    model.machine_terms.terms.iter().flat_map(|t| t.term.signals()).any(|s| matches!(&s, SignalKind::Temperature(n) | SignalKind::TemperatureHistory(n) if n == name))
}

fn has_lag(model: &CellModel) -> bool {
    model.machine_terms.terms.iter().any(|t| {
        t.term
            .signals()
            .iter()
            .any(|s| matches!(s, SignalKind::TemperatureHistory(_)))
    })
}

/// Everything a written model is put through (module docs). `bag`: the recording; `points`:
/// the recording with measured points (the tracker node's, for cartesian and delta machines; a
/// stationing program's own).
fn read_back(
    dir: &Path,
    what: &str,
    output: &str,
    bag: &str,
    points: Option<&str>,
    temperatures: &[String],
) {
    let path = dir.join(output);
    let model = CellModel::from_path(&path)
        .unwrap_or_else(|e| panic!("{what}: {output} does not read as a model: {e}"));
    let stem = output.replace(['/', '.'], "_");
    // calibrate and diagnose take it
    ok(
        dir,
        what,
        "metrocell",
        &[
            "calibrate",
            "--model",
            output,
            bag,
            "-o",
            &format!("{stem}.again.yaml"),
        ],
    );
    // (without empirical corrections, half of diagnose's time: they have no part in a model file)
    ok(
        dir,
        what,
        "metrocell",
        &[
            "diagnose",
            "--model",
            output,
            bag,
            "--json",
            &format!("{stem}.json"),
            "--no-empirical",
        ],
    );
    // compensation: from the recording's temperatures, and at given ones (a steady state)
    let xyz = matches!(
        model.raw.machine.family,
        metrocell_twin::cell_file::MachineFamily::Cartesian
            | metrocell_twin::cell_file::MachineFamily::Delta
    );
    let program = if xyz {
        part_program(&model.machine.travel)
    } else {
        "G21 G90\nG1 X0 Y0 Z0\n".to_string()
    };
    std::fs::write(dir.join("part.nc"), program).unwrap();
    let gcode = [
        "compensate",
        "gcode",
        "--model",
        output,
        "part.nc",
        "-o",
        &format!("{stem}.nc"),
        "--temperatures-from",
        bag,
    ];
    let mut table: Vec<&str> = vec![
        "compensate",
        "table",
        "--model",
        output,
        "-o",
        &stem,
        "--step",
        "50",
    ];
    // a steady state at 20.5 °C for every sensor the model's terms read (and only those)
    let given: Vec<String> = temperatures
        .iter()
        .filter(|t| reads(&model, t))
        .map(|t| format!("--temperature={t}=20.5"))
        .collect();
    table.extend(given.iter().map(String::as_str));
    for (args, which) in [(&gcode[..], "gcode"), (&table[..], "table")] {
        let (code, out, err) = run(dir, "metrocell", args);
        if xyz {
            assert_eq!(
                code, 0,
                "{what}: compensate {which} of {output}\n{out}{err}"
            );
            if which == "gcode" {
                assert!(
                    out.contains(&format!("temperatures from {bag}")),
                    "{what}: {out}"
                );
            } else {
                assert_eq!(out.contains("steady state assumed"), has_lag(&model), "{what}: compensate table of {output} says whether a steady state is assumed:\n{out}");
            }
        } else {
            assert_eq!(
                code, 2,
                "{what}: compensate {which} of a jointed machine is refused\n{out}{err}"
            );
            assert!(
                err.contains("cartesian") && err.contains("delta"),
                "{what}: the refusal names the families it serves: {err}"
            );
        }
    }
    // the simulator takes it, or names the pose it needs
    let (code, out, err) = run(
        dir,
        "metrocell",
        &[
            "sim",
            "--cell",
            output,
            "--duration",
            "1min",
            "--no-camera-frames",
            "--quiet",
            "-o",
            &format!("{stem}.sim"),
        ],
    );
    let stationing = model
        .raw
        .program
        .as_ref()
        .is_some_and(|p| p.stationing.is_some());
    let tracker_without_pose = model
        .raw
        .sensors
        .tracker
        .as_ref()
        .is_some_and(|t| t.pose.is_none())
        && !stationing;
    if model.raw.environment.is_none() || model.raw.program.is_none() {
        assert_ne!(code, 0, "{what}: sim of {output}");
        assert!(
            err.contains("required to simulate")
                && (err.contains("environment") || err.contains("program")),
            "{what}: {err}"
        );
    } else if tracker_without_pose {
        assert_ne!(code, 0, "{what}: sim of {output}");
        assert!(
            err.contains("sensors.tracker.pose") && err.contains("required to simulate"),
            "{what}: {err}"
        );
    } else {
        assert_eq!(code, 0, "{what}: sim --cell {output}\n{out}{err}");
    }
    // the estimator node takes it
    let model_param = format!("model:={}", path.display());
    let input = points.unwrap_or(bag);
    let (code, out, err) = run(
        dir,
        "metrocell-estimator",
        &[
            "--bag",
            input,
            "--output",
            &format!("{stem}.estimated"),
            "--ros-args",
            "-p",
            &model_param,
        ],
    );
    assert!(
        err.contains(&format!("model {}: ", path.display())) || points.is_none(),
        "{what}: the estimator read the model\n{err}"
    );
    match points {
        Some(_) => {
            assert_eq!(code, 0, "{what}: estimator on {output}\n{out}{err}");
            let published: u64 = err
                .split(" models published")
                .next()
                .and_then(|s| s.rsplit(' ').next())
                .and_then(|n| n.parse().ok())
                .unwrap_or(0);
            assert!(
                published > 0,
                "{what}: the estimator published no model from {output}:\n{err}"
            );
        }
        None => {
            assert_ne!(
                code, 0,
                "{what}: estimator on a recording without measured points"
            );
            assert!(
                err.contains("no measured points")
                    && err.contains("/measured_points")
                    && !err.contains("cell file"),
                "{what}: the model is taken, the missing input named:\n{err}"
            );
        }
    }
}

/// The example cells' URDFs into `dir`, where a copied model file looks for them.
fn copy_urdfs(dir: &Path) {
    let cells = workspace_root().join("crates/twin/examples/cells");
    for e in std::fs::read_dir(&cells).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "urdf") {
            std::fs::copy(&p, dir.join(p.file_name().unwrap())).unwrap();
        }
    }
}

fn one_row(base: &Path, row: &Row) {
    let dir = base.join(row.name.replace('/', "_"));
    std::fs::create_dir_all(&dir).unwrap();
    copy_urdfs(&dir);
    std::fs::write(dir.join("recorded_cell.yaml"), &row.recorded_cell).unwrap();
    ok(
        &dir,
        &row.name,
        "metrocell",
        &[
            "sim",
            "--cell",
            "recorded_cell.yaml",
            "--duration",
            row.duration,
            "--seed",
            "1",
            "--no-camera-frames",
            "--quiet",
            "-o",
            "bag",
        ],
    );
    let recorded = CellModel::from_path(dir.join("recorded_cell.yaml")).unwrap();
    let temperatures: Vec<String> = recorded
        .raw
        .sensors
        .thermocouples
        .iter()
        .map(|t| t.name.clone())
        .collect();
    let xyz = matches!(
        recorded.raw.machine.family,
        metrocell_twin::cell_file::MachineFamily::Cartesian
            | metrocell_twin::cell_file::MachineFamily::Delta
    );
    let points = if xyz {
        let offset = recorded.machine.tool_offset;
        let offset = format!("tool_offset:=[{}, {}, {}]", offset.x, offset.y, offset.z);
        ok(
            &dir,
            &row.name,
            "metrocell-tracker",
            &[
                "--bag",
                "bag",
                "--output",
                "tracked",
                "--ros-args",
                "-p",
                &offset,
                "-p",
                "registration_points:=4",
            ],
        );
        ok(
            &dir,
            &row.name,
            "metrocell",
            &["bag", "merge", "points", "bag", "tracked"],
        );
        Some("points")
    } else if recorded
        .raw
        .program
        .as_ref()
        .is_some_and(|p| p.stationing.is_some())
    {
        // a stationing program records its points itself
        Some("bag")
    } else {
        None
    };
    for (style, text) in [
        ("as written", row.model.clone()),
        ("block style", block_style(&row.model)),
    ] {
        let what = format!("{} ({style})", row.name);
        let sub = dir.join(style.replace(' ', "_"));
        std::fs::create_dir_all(&sub).unwrap();
        for link in ["bag", "points"] {
            if dir.join(link).exists() {
                std::os::unix::fs::symlink(dir.join(link), sub.join(link)).unwrap();
            }
        }
        copy_urdfs(&sub);
        std::fs::write(sub.join("model.yaml"), &text).unwrap();
        ok(
            &sub,
            &what,
            "metrocell",
            &[
                "calibrate",
                "--model",
                "model.yaml",
                "bag",
                "-o",
                "calibrated.yaml",
            ],
        );
        ok(
            &sub,
            &what,
            "metrocell",
            &[
                "diagnose",
                "--model",
                "model.yaml",
                "bag",
                "--report",
                "diagnosis",
            ],
        );
        if row.name.ends_with("demo_model.yaml") {
            // the case of issue 32 item 1: a warm-up found for a model without a tracker
            let augmented = CellModel::from_path(sub.join("diagnosis/model.yaml")).unwrap();
            let tracker = augmented.raw.sensors.tracker.as_ref().unwrap_or_else(|| {
                panic!("{what}: diagnose found no tracker warm-up in demo_shift's 20 min")
            });
            assert!(tracker.warmup.is_some() && tracker.pose.is_none(), "{what}");
        }
        for output in ["calibrated.yaml", "diagnosis/model.yaml"] {
            let written = std::fs::read_to_string(sub.join(output)).unwrap();
            if style == "block style" {
                // a block list stays one (issue 32 item 2: `translation:` then `- [x, y, z]`)
                assert!(
                    !written
                        .lines()
                        .any(|l| l.trim_start().starts_with("- [") && l.contains(" m")),
                    "{what}: {output} has a list in a list:\n{written}"
                );
            }
            read_back(
                &sub,
                &format!("{what} → {output}"),
                output,
                "bag",
                points,
                &temperatures,
            );
        }
    }
}

#[test]
fn every_written_model_reads_back_in_every_command() {
    let started = Instant::now();
    let base = scratch();
    let rows = rows();
    assert!(
        rows.len() >= 7,
        "every example cell: {:?}",
        rows.iter().map(|r| &r.name).collect::<Vec<_>>()
    );
    // two rows at a time, the slowest (xfyz_shift's 75 parameters) first
    let mut order: Vec<&Row> = rows.iter().collect();
    order.sort_by_key(|r| r.name.contains("xfyz"));
    let queue = Mutex::new(order);
    let failures = Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get().clamp(1, 2));
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let Some(row) = queue.lock().unwrap().pop() else {
                    break;
                };
                let t = Instant::now();
                if let Err(e) = std::panic::catch_unwind(|| one_row(&base, row)) {
                    let msg = e
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    failures
                        .lock()
                        .unwrap()
                        .push(format!("{}: {msg}", row.name));
                }
                eprintln!("{}: {:.1} s", row.name, t.elapsed().as_secs_f64());
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} rows failed:\n{}",
        failures.len(),
        rows.len(),
        failures.join("\n\n")
    );
    eprintln!(
        "{} models × 2 styles round-tripped in {:.1} s",
        rows.len(),
        started.elapsed().as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&base);
}
