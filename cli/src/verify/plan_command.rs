//! `metrocell verify plan`: the points, their order, the machine program and the tracker's
//! station for a volumetric verification (seed 001, P2–P5), written to a directory.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use metrocell_estimation::simulated_records::TrackerNoise;
use metrocell_physics::units::{parse_quantity, split_quantity};
use metrocell_twin::CellModel;
use metrocell_verification::identification_model::multi_target_model_yaml;
use metrocell_verification::length_lines::with_length_lines;
use metrocell_verification::machine_program::{
    arrival_times, gcode, multi_reflector_gcode, stops, DwellWord, ProgramSettings,
};
use metrocell_verification::tracker_station::{
    assess, candidate_ring, facing, ranked, target_points, SightLimits, Station, StationAssessment,
};
use metrocell_verification::visiting_order::spiral_order;
use metrocell_verification::Mesh;
use nalgebra::Vector3;

#[derive(clap::Args)]
#[command(after_long_help = HELP)]
pub struct PlanArgs {
    /// X range of the mesh: MIN..MAX (a bare number is mm), e.g. 800..1200 or 0.8m..1.2m
    #[arg(long, value_parser = parse_range, allow_hyphen_values = true)]
    x: (f64, f64),
    /// Y range of the mesh
    #[arg(long, value_parser = parse_range, allow_hyphen_values = true)]
    y: (f64, f64),
    /// Z range of the mesh (one value, e.g. 200..200, for a single plane)
    #[arg(long, value_parser = parse_range, allow_hyphen_values = true)]
    z: (f64, f64),
    /// Distance between mesh points
    #[arg(long, value_parser = parse_quantity_arg("m"))]
    step: f64,
    /// The error model the station is judged with (a cell file with `terms:` and
    /// `sensors.tracker.pose`); default: each axis's positioning and straightnesses (cubic) and
    /// the squarenesses, what one tracker target identifies
    #[arg(long)]
    model: Option<PathBuf>,
    /// Judge this tracker station only (x,y,z in the model's frame, a bare number is mm) instead
    /// of searching candidates; the plan is refused if it cannot see every point
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    station: Option<Vector3<f64>>,
    /// Feed of every move
    #[arg(long, default_value = "1000mm/min", value_parser = parse_quantity_arg("m/s"))]
    feed: f64,
    /// Dwell at each point while the tracker measures
    #[arg(long, default_value = "5s", value_parser = parse_quantity_arg("s"))]
    dwell: f64,
    /// Length of the last move to each point, in + on every axis (larger than the backlash); 0: none
    #[arg(long, default_value = "2mm", value_parser = parse_quantity_arg("m"))]
    approach: f64,
    /// How the controller spells a dwell in seconds: P (LinuxCNC, Haas), X (Fanuc), S (Marlin, Klipper)
    #[arg(long, default_value = "P", value_parser = ["P", "X", "S"])]
    dwell_word: String,
    /// Revisit the first point (the warm-up nest) after every this many points; 0: never
    #[arg(long, default_value_t = 10)]
    nest_every: usize,
    /// Add to the grid a line of six points through the volume's centre along each axis and
    /// each space diagonal, so the report's length test has its five lengths in all seven
    /// directions (ISO 10360-2's 35 lengths, 105 measurements over three cycles); a short axis
    /// or a diagonal of a regular grid holds fewer
    #[arg(long)]
    length_test: bool,
    /// The reflector's offsets on the spindle, from its gauge point, one pass of the program
    /// each: x,y,z;x,y,z;… (a bare number is mm), e.g. "0,0,-100;150,0,-100;0,0,-250". Two or
    /// more separate roll, pitch and yaw from straightness (their Abbe arms differ): the default
    /// model then declares the nine angular errors, the map is for the first offset, and the
    /// program stops (M0) before each pass for the reflector to be moved and its offset published
    /// on /machine/tool_offset. Offsets along two directions across each axis of turn are needed:
    /// one along the spindle (z) and one across it (x or y) separates all nine
    #[arg(long, value_parser = parse_reflectors, allow_hyphen_values = true)]
    reflectors: Option<Reflectors>,
    /// The tracker's shortest range
    #[arg(long, default_value = "0.5m", value_parser = parse_quantity_arg("m"))]
    min_range: f64,
    /// The tracker's longest range
    #[arg(long, default_value = "15m", value_parser = parse_quantity_arg("m"))]
    max_range: f64,
    /// The reflector's acceptance half-angle (P5 evaluates ±15°)
    #[arg(long, default_value = "15deg", value_parser = parse_quantity_arg("rad"))]
    acceptance: f64,
    /// Range noise a of σ = a + b·range (thesis P3: 4 um)
    #[arg(long, default_value = "4um", value_parser = parse_quantity_arg("m"))]
    range_noise: f64,
    /// Range noise b of σ = a + b·range (thesis P3: 0.8 um/m)
    #[arg(long, default_value = "0.8um/m", value_parser = parse_quantity_arg("m/m"))]
    range_noise_per_metre: f64,
    /// Angular noise σ of azimuth and elevation
    #[arg(long, default_value = "3urad", value_parser = parse_quantity_arg("rad"))]
    angular_noise: f64,
    /// Directory to write the plan into (created)
    #[arg(short, long)]
    output: PathBuf,
}

const HELP: &str = "\
What it writes into OUTPUT:
  program.ngc          the machine program: every point approached in + on each axis over the last
                       --approach (backlash then shifts every point alike, into the origin), a dwell
                       while the tracker measures, the first point revisited as the warm-up nest;
                       each point's name (p0, p1, …, nest) is in a comment: name the tracker's
                       measurement after it
  points.csv           stop, name, x_mm, y_mm, z_mm, arrival_s (T_v = L_T/F + T_s(n − 1), from the
                       start of the program — or of its pass — at the first point), pass and the
                       reflector's offset (mm)
  stations.csv         every candidate station, best first: whether it sees every point (range,
                       the reflector's acceptance), the largest and mean standard uncertainty of
                       the identified error map over the mesh, the parameters it cannot identify
  verify.launch.yaml   the run: the tracker node (TCP stream) and the recorder
  model.yaml           the error model the stations were judged with

With --reflectors (two or more offsets of the reflector on the spindle): one pass of the stops
per offset, each after a program stop (M0) at which the reflector is moved and its offset
published on /machine/tool_offset (geometry_msgs/PointStamped, m; the M0's comment has the
command), so `verify report` gives each reading its target; the default model then declares
the roll, pitch and yaw of each axis (quadratic) with the P5 chain's Abbe arms, and its tool is
the first offset — the map `verify report` states is for it.

How stations are judged: the readings of every point from the station, with the tracker's noise
model, identify the model's errors together with the tracker's pose; the error map's σ at each
point follows from that fit's covariance (linearised; `verify report` samples it by Monte Carlo).
Candidates stand on circles of 1, 1.5, 2.5 and 4 m around the mesh, 0.3 and 0.8 m above its
centre, facing it; the reflector is aimed at the station from the mesh's centre.

Examples:
  metrocell verify plan --x 800..1200 --y 100..500 --z 200..400 --step 100mm -o plan
  metrocell verify plan --x 800..1200 --y 100..500 --z 200..400 --step 100mm --length-test -o plan   # + 28 points on this mesh: the report's length test has all 105 measurements
  metrocell verify plan --x 0..400 --y 0..400 --z 0..0 --step 50mm --station=-863.5,194.4,677.8 -o p3
  metrocell verify plan --x 0..800 --y 0..500 --z 0..400 --step 100mm --model my_21_errors.yaml -o plan
  metrocell verify plan --x 0..800 --y 0..500 --z 0..400 --step 100mm --reflectors \"0,0,-100;150,0,-100;0,0,-250\" -o plan   # the 21 errors: three passes";

fn parse_quantity_arg(unit: &'static str) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |s: &str| {
        let v = parse_quantity(s.trim(), unit).map_err(|_| {
            format!("`{s}` is not a quantity in {unit} (e.g. 100mm, 5s, 1000mm/min, 15deg)")
        })?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!(
                "`{s}` must be a finite, non-negative quantity in {unit}"
            ));
        }
        Ok(v)
    }
}

/// A length where a bare number is millimetres; may be negative.
fn length_mm(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let text = if split_quantity(t).1.is_empty() {
        format!("{t} mm")
    } else {
        t.to_string()
    };
    parse_quantity(&text, "m").map_err(|_| format!("`{s}` is not a length (e.g. 800, 800mm, 0.8m)"))
}

fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("`{s}`: give a range MIN..MAX, e.g. 800..1200"))?;
    Ok((length_mm(a)?, length_mm(b)?))
}

/// The reflector offsets of `--reflectors` (one value to clap, so not a `Vec` it would repeat).
#[derive(Debug, Clone)]
struct Reflectors(Vec<Vector3<f64>>);

fn parse_reflectors(s: &str) -> Result<Reflectors, String> {
    let v: Vec<Vector3<f64>> = s
        .split(';')
        .filter(|p| !p.trim().is_empty())
        .map(parse_point)
        .collect::<Result<_, _>>()?;
    if v.is_empty() {
        return Err(format!(
            "`{s}`: give x,y,z;x,y,z;…, e.g. 0,0,-100;150,0,-100;0,0,-250"
        ));
    }
    Ok(Reflectors(v))
}

fn parse_point(s: &str) -> Result<Vector3<f64>, String> {
    let v: Vec<f64> = s.split(',').map(length_mm).collect::<Result<_, _>>()?;
    if v.len() != 3 {
        return Err(format!("`{s}`: give x,y,z, e.g. -863.5,194.4,677.8"));
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

pub fn run(a: PlanArgs) -> Result<i32> {
    let mesh = Mesh {
        min: [a.x.0, a.y.0, a.z.0],
        max: [a.x.1, a.y.1, a.z.1],
        step: a.step,
    };
    let grid = if a.length_test {
        with_length_lines(&mesh)?
    } else {
        mesh.points()?
    };
    let order = spiral_order(&grid);
    let points: Vec<[f64; 3]> = order.iter().map(|&i| grid[i]).collect();
    let reflectors = a.reflectors.clone().map(|r| r.0).unwrap_or_default();
    let model_text = match &a.model {
        Some(p) => std::fs::read_to_string(p)
            .with_context(|| format!("cannot read the model {}", p.display()))?,
        None => multi_target_model_yaml(&mesh, &reflectors),
    };
    let model_path = a
        .model
        .clone()
        .unwrap_or_else(|| PathBuf::from("model.yaml"));
    let base = model_path.parent().unwrap_or(Path::new("."));
    let cell = CellModel::from_yaml_str_in(&model_text, &model_path.display().to_string(), base)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let fm = cell.forward_model().map_err(|e| anyhow::anyhow!("{e}"))?;
    let at = fm.params();
    // each reflector as the readings will carry it: its offset from the model's tool
    let shifts: Vec<Vector3<f64>> = reflectors
        .iter()
        .map(|r| r - fm.machine.tool_offset)
        .collect();
    let noise = TrackerNoise {
        constant: a.range_noise,
        per_metre: a.range_noise_per_metre,
        angular: a.angular_noise,
    };
    let limits = SightLimits {
        min_range: a.min_range,
        max_range: a.max_range,
        acceptance: a.acceptance,
        reflector_facing: None,
    };
    let targets = target_points(&fm, &at, &points).map_err(anyhow::Error::msg)?;
    let centre = targets.iter().sum::<Vector3<f64>>() / targets.len() as f64;
    let candidates: Vec<Station> = match a.station {
        Some(p) => vec![facing(p, centre)],
        None => candidate_ring(centre, &[1.0, 1.5, 2.5, 4.0], &[0.3, 0.8], 12),
    };
    eprintln!(
        "judging {} tracker station(s) for {} points…",
        candidates.len(),
        points.len()
    );
    let assessed: Vec<StationAssessment> = candidates
        .iter()
        .map(|s| assess(&fm, &cell.setup, &at, &points, &shifts, s, &limits, noise))
        .collect::<Result<_, _>>()
        .map_err(anyhow::Error::msg)?;
    let rank = ranked(&assessed);
    let best = &assessed[rank[0]];
    if !best.sees_all() {
        let why: Vec<String> = best.blocked.iter().take(5).map(|b| b.to_string()).collect();
        bail!(
            "the tracker cannot see every point from {}: {}{} — move the station (--station), \
             or change the limits (--min-range, --max-range, --acceptance) if your tracker and \
             reflector allow it",
            if a.station.is_some() {
                "the given station"
            } else {
                "any candidate station"
            },
            why.join("; "),
            if best.blocked.len() > 5 {
                format!(" (and {} more)", best.blocked.len() - 5)
            } else {
                String::new()
            }
        );
    }
    let settings = ProgramSettings {
        feed: a.feed,
        dwell: a.dwell,
        approach: a.approach,
        dwell_word: match a.dwell_word.as_str() {
            "X" => DwellWord::X,
            "S" => DwellWord::S,
            _ => DwellWord::P,
        },
        nest_every: a.nest_every,
    };
    let plan_stops = stops(&points, a.nest_every);
    let home = points[0];
    let arrivals = arrival_times(&plan_stops, home, &settings);
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("cannot create {}", a.output.display()))?;
    let title = format!(
        "metrocell verify plan: {} points, X {}..{} Y {}..{} Z {}..{} mm at {} mm; tracker at ({:.0}, {:.0}, {:.0}) mm",
        points.len(),
        a.x.0 * 1e3,
        a.x.1 * 1e3,
        a.y.0 * 1e3,
        a.y.1 * 1e3,
        a.z.0 * 1e3,
        a.z.1 * 1e3,
        a.step * 1e3,
        best.station.position.x * 1e3,
        best.station.position.y * 1e3,
        best.station.position.z * 1e3
    );
    let write = |name: &str, text: &str| -> Result<()> {
        let p = a.output.join(name);
        std::fs::write(&p, text).with_context(|| format!("cannot write {}", p.display()))
    };
    let program = if reflectors.len() > 1 {
        let r: Vec<[f64; 3]> = reflectors.iter().map(|v| [v.x, v.y, v.z]).collect();
        multi_reflector_gcode(&plan_stops, &settings, &title, &r)
    } else {
        gcode(&plan_stops, &settings, &title)
    };
    write("program.ngc", &program)?;
    // arrival: s after the program (or its pass, after the M0) starts at the first point
    let mut csv = String::from(
        "stop,name,x_mm,y_mm,z_mm,arrival_s,pass,reflector_x_mm,reflector_y_mm,reflector_z_mm\n",
    );
    let passes: Vec<Vector3<f64>> = if reflectors.len() > 1 {
        reflectors.clone()
    } else {
        vec![fm.machine.tool_offset]
    };
    let mut k = 0;
    for (pass, r) in passes.iter().enumerate() {
        for (s, t) in plan_stops.iter().zip(&arrivals) {
            let _ = writeln!(
                csv,
                "{k},{},{:.4},{:.4},{:.4},{t:.3},{},{:.4},{:.4},{:.4}",
                s.name,
                s.point[0] * 1e3,
                s.point[1] * 1e3,
                s.point[2] * 1e3,
                pass + 1,
                r.x * 1e3,
                r.y * 1e3,
                r.z * 1e3
            );
            k += 1;
        }
    }
    write("points.csv", &csv)?;
    let mut st = String::from("rank,x_mm,y_mm,z_mm,yaw_deg,sees_all,blocked_points,min_range_m,max_range_m,max_incidence_deg,max_sd_um,mean_sd_um,held\n");
    for (r, &i) in rank.iter().enumerate() {
        let s = &assessed[i];
        let _ = writeln!(
            st,
            "{},{:.1},{:.1},{:.1},{:.2},{},{},{:.3},{:.3},{:.2},{:.3},{:.3},{}",
            r + 1,
            s.station.position.x * 1e3,
            s.station.position.y * 1e3,
            s.station.position.z * 1e3,
            s.station.yaw.to_degrees(),
            s.sees_all(),
            s.blocked.len(),
            s.ranges.0,
            s.ranges.1,
            s.max_incidence.to_degrees(),
            s.max_sd * 1e6,
            s.mean_sd * 1e6,
            s.held.join(" ")
        );
    }
    write("stations.csv", &st)?;
    write("model.yaml", &model_text)?;
    write(
        "verify.launch.yaml",
        &launch_file(&title, a.nest_every > 0, points.len()),
    )?;
    let total = arrivals.last().copied().unwrap_or(0.0) + a.dwell;
    println!("{title}");
    if reflectors.len() > 1 {
        println!(
            "  {} passes, one per reflector offset ({}), after a program stop (M0) each: move the reflector, publish its offset on /machine/tool_offset (the command is in the M0's comment); the map is for the first",
            reflectors.len(),
            reflectors
                .iter()
                .map(|r| format!("({:.1}, {:.1}, {:.1}) mm", r.x * 1e3, r.y * 1e3, r.z * 1e3))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    println!(
        "  {} stops ({} points{}), {:.1} min{} at {:.0} mm/min with {} s dwells",
        plan_stops.len(),
        points.len(),
        if a.nest_every > 0 {
            format!(", the nest revisited every {} points", a.nest_every)
        } else {
            String::new()
        },
        total / 60.0,
        if reflectors.len() > 1 { " a pass" } else { "" },
        a.feed * 60e3,
        a.dwell
    );
    println!(
        "  tracker station: ({:.0}, {:.0}, {:.0}) mm, facing {:.1}° — ranges {:.2}–{:.2} m, \
         reflector incidence up to {:.1}°",
        best.station.position.x * 1e3,
        best.station.position.y * 1e3,
        best.station.position.z * 1e3,
        best.station.yaw.to_degrees(),
        best.ranges.0,
        best.ranges.1,
        best.max_incidence.to_degrees()
    );
    println!(
        "  identified error map: largest σ {:.2} µm, mean {:.2} µm over the points (linearised, k = 1)",
        best.max_sd * 1e6,
        best.mean_sd * 1e6
    );
    if !best.held.is_empty() {
        println!(
            "  not identifiable from these readings, held at their start (their values are conventions): {}",
            best.held.join(", ")
        );
    }
    let seeing = assessed.iter().filter(|s| s.sees_all()).count();
    println!(
        "  {seeing} of {} candidate stations see every point; all of them in {}",
        assessed.len(),
        a.output.join("stations.csv").display()
    );
    println!(
        "  wrote program.ngc, points.csv, stations.csv, model.yaml, verify.launch.yaml in {}",
        a.output.display()
    );
    Ok(0)
}

/// The launch file of the run: the tracker node reading the instrument's stream, and the recorder.
fn launch_file(title: &str, nest: bool, points: usize) -> String {
    format!(
        "# {title}
# Start it on the cell's computer, then run program.ngc on the machine; stop with Ctrl-C after
# the last dwell. The tracker node pairs each dwell with the commanded position the controller
# streams on machine/commanded_joint_states (joints x, y, z in m); the recorder writes it all.
#
#   metrocell launch verify.launch.yaml tracker_address:=192.168.0.20:5000 output:=verify_bag
launch:
- arg: {{name: tracker_address, default: \"127.0.0.1:5000\", description: \"host:port of the tracker's line stream\"}}
- arg: {{name: output, default: \"verify_bag\", description: \"bag directory the recorder writes\"}}
- node:
    pkg: metrocell
    exec: metrocell-tracker
    name: tracker
    param:
    - {{name: backend, value: tcp}}
    - {{name: tcp_address, value: \"$(var tracker_address)\"}}
    - {{name: registration_points, value: {reg}}}
{warmup}- node:
    pkg: metrocell
    exec: metrocell-recorder
    name: recorder
    param:
    - {{name: output, value: \"$(var output)\"}}
    - {{name: flush_interval, value: 0.5}}
",
        reg = points.clamp(3, 12),
        warmup = if nest {
            "    - {name: warmup_target, value: nest}   # the first point, revisited: the warm-up curve\n"
        } else {
            ""
        }
    )
}
