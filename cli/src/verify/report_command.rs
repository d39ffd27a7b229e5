//! `metrocell verify report --model MODEL.yaml BAG... -o DIR`: a verification's readings
//! identified, its uncertainty by Monte Carlo, the length test and the ISO/TS 15530-3 budget,
//! on one HTML page a metrologist signs, with the numbers in verification.json and map.csv.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use metrocell_estimation::error_functions::axis_error_functions;
use metrocell_estimation::fit_summary::{summary_lines, value_with_sigma};
use metrocell_estimation::map_gauge::MapGauge;
use metrocell_estimation::uncertainty_budget::{
    standard_uncertainty_of_mean, thermal_expansion_uncertainty, Budget,
};
use metrocell_estimation::volumetric_monte_carlo::{error_map, mean_sd};
use metrocell_estimation::{fit, FitOptions};
use metrocell_model_file::CellModel;
use metrocell_physics::units::parse_quantity;
use metrocell_records::{records_from_bags, PointSource, RecordingOptions};
use metrocell_report::{HistogramPlot, Report, Series, SeriesPlot, Table};
use metrocell_verification::length_test::{length_cases, Decision, Mpe};
use metrocell_verification::measured_lengths::{
    at_rest, measured_lengths, mesh_of, visits, visits_of_one_target,
};
use metrocell_verification::reference_conditions::at_reference_temperature;
use metrocell_verification::resampled_monte_carlo::resampled_monte_carlo;
use nalgebra::Vector3;

#[derive(clap::Args)]
#[command(after_long_help = HELP)]
pub struct ReportArgs {
    /// The error model to identify (a cell file with `terms:`; `verify plan` writes model.yaml)
    #[arg(long)]
    model: PathBuf,
    /// The verification's recordings (rosbag2 directories or .mcap files)
    #[arg(required = true)]
    bags: Vec<PathBuf>,
    /// Directory to write the report into (created)
    #[arg(short, long)]
    output: PathBuf,
    /// Monte Carlo trials (seed 001 P3 used 1000)
    #[arg(long, default_value_t = 200)]
    trials: usize,
    /// Seed of the Monte Carlo's noise
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The MPE of a length measurement, ±min(A + L/K, B): A (e.g. 5um)
    #[arg(long, value_parser = quantity("m"))]
    mpe_a: Option<f64>,
    /// K of the MPE (L in mm gives µm, as specifications write it: 5 + L/200 µm has K = 200)
    #[arg(long)]
    mpe_k: Option<f64>,
    /// B of the MPE, the cap (e.g. 20um); alone: MPE = ±B
    #[arg(long, value_parser = quantity("m"))]
    mpe_b: Option<f64>,
    /// The tracker's calibration uncertainty (k = 1) per metre of range (seed 001: U = 5.6 ppm at k = 2)
    #[arg(long, default_value = "2.8um/m", value_parser = quantity("1"))]
    tracker_u_per_metre: f64,
    /// The tracker's distance to the mesh, for u_cal when the readings are machine-frame points
    /// (tracker-frame readings carry their range)
    #[arg(long, value_parser = quantity("m"))]
    tracker_range: Option<f64>,
    /// Include the probe-tip check on the page: CSV angle_deg,x_mm,y_mm,z_mm (see `verify probe-tip`)
    #[arg(long)]
    probe_tip: Option<PathBuf>,
    /// Include a hole plate's result on the page: the JSON `verify plate --json` wrote
    #[arg(long)]
    plate: Option<PathBuf>,
    /// Uncertainty of the scales' expansion coefficient (seed 001: 0.002/(2√3) µm/(mm·K) = 5.77e-7 1/K)
    #[arg(long, default_value = "5.77e-7 1/K", value_parser = quantity("1/K"))]
    alpha_u: f64,
}

const HELP: &str = "\
What it does:
  1. identifies the model's errors and the tracker's pose from the bags' tracker readings taken
     while the machine stood at a point (3 or more readings at one commanded position; readings
     on the move are left out), as `metrocell calibrate` does (robust least squares, what cannot
     be separated held and named);
  2. Monte Carlo (seed 001 P3 on your data): the fitted errors generate each trial's readings with
     every reading's noise drawn from its stated covariance; each trial is identified again; the
     spread of the error maps is their uncertainty u (k = 1) at each mesh point, and generating −
     refitted map is the residual volumetric error a compensation from this verification leaves.
     The map is the machine at 20 °C (ISO 1): a model's thermal terms (thermal_scale,
     thermal_growth) are identified with it and their coefficients say what temperature adds.
     A tracker beside the machine fixes the map only up to a rigid motion (its own pose is
     identified with it): the map is stated with its best-fit rigid motion over the mesh
     removed, the machine's axes as the verified volume defines them. Readings of the reflector at
     other offsets on the spindle (recorded on /machine/tool_offset; `verify plan --reflectors`)
     are each fitted at their target, the angular errors through their longer Abbe arms: that is
     what separates roll, pitch and yaw from straightness. The map is for the model's tool
     (machine.tool_offset);
  3. the length test (ISO 10360-2 manner): 5 lengths × 7 directions × 3 repetitions between mesh
     points of one target (the model's tool when it was measured), measured from the visits'
     mean points (the tracker's identified errors, such as its warm-up, taken out), as the machine is and with the identified model compensated at each
     visit's temperatures, each with U (k = 2); with --mpe-* each is judged by ISO 14253-1
     (conforms / does not conform / not proven);
  4. the ISO/TS 15530-3 budget: u_cal (tracker calibration × mean range), u_p (the Monte Carlo's
     residual, per coordinate), u_b (its systematic part, σ/√trials), u_w (the scales' expansion
     coefficient's uncertainty × the temperature's distance from 20 °C × the mesh's diagonal);
  5. writes DIR/index.html (figures, tables, the bag it came from), DIR/map.csv (each point's
     error and u), DIR/verification.json (the figures, every identified parameter with its σ).

Examples:
  metrocell verify plan --x 800..1200 --y 100..500 --z 200..400 --step 100mm -o plan
  metrocell verify report --model plan/model.yaml verify_bag -o verify_report
  metrocell verify report --model plan/model.yaml verify_bag -o rep --mpe-a 5um --mpe-k 200 --mpe-b 20um --trials 1000";

fn quantity(unit: &'static str) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |s: &str| {
        parse_quantity(s.trim(), unit)
            .map_err(|_| format!("`{s}` is not a quantity in {unit}"))
            .and_then(|v| {
                if v.is_finite() && v >= 0.0 {
                    Ok(v)
                } else {
                    Err(format!("`{s}` must be finite and ≥ 0"))
                }
            })
    }
}

/// The targets the fit's readings sighted: each distinct tool offset (the model's plus the
/// reading's shift, m) and how many readings it has, in first-seen order.
fn target_offsets(
    records: &metrocell_estimation::RecordSet,
    f: &metrocell_estimation::Fit,
    fm: &metrocell_model::ForwardModel,
) -> Vec<(Vector3<f64>, usize)> {
    let mut out: Vec<(Vector3<f64>, usize)> = vec![];
    for &i in &f.used {
        let t = fm.machine.tool_offset
            + records.records[i]
                .signals
                .tool_offset_shift
                .unwrap_or_default();
        match out.iter_mut().find(|(o, _)| (o - t).norm() < 1e-6) {
            Some(o) => o.1 += 1,
            None => out.push((t, 1)),
        }
    }
    out
}

fn mpe_of(a: &ReportArgs) -> Result<Option<Mpe>> {
    Ok(match (a.mpe_a, a.mpe_k, a.mpe_b) {
        (None, None, None) => None,
        (Some(a), Some(k), Some(b)) => Some(Mpe::Capped { a, k, b }),
        (Some(a), Some(k), None) => Some(Mpe::Linear { a, k }),
        (None, None, Some(b)) => Some(Mpe::Constant { b }),
        _ => bail!("give the MPE as --mpe-a and --mpe-k (± A + L/K), with --mpe-b to cap it, or --mpe-b alone (± B)"),
    })
}

pub fn run(a: ReportArgs) -> Result<i32> {
    let started = Instant::now();
    let mpe = mpe_of(&a)?;
    // the checks signed with it, read first: a bad file stops the report before it is written
    let extras = extra_checks(&a)?;
    if a.trials < 10 {
        bail!("--trials {}: a Monte Carlo needs at least 10 trials to state a spread (seed 001 used 1000)", a.trials);
    }
    let model = CellModel::from_path(&a.model)?;
    let fm = model.forward_model()?;
    eprintln!("reading {} recording(s)…", a.bags.len());
    let options = RecordingOptions {
        points: PointSource::Auto,
        ..RecordingOptions::default()
    };
    let all = records_from_bags(&a.bags, &fm, &options)?;
    let records = at_rest(&all, 3);
    if records.records.len() < all.records.len() {
        eprintln!(
            "{} of {} readings were taken while the machine stood at a point; the {} taken on the move are left out",
            records.records.len(),
            all.records.len(),
            all.records.len() - records.records.len()
        );
    }
    if records.records.is_empty() {
        bail!("the recordings hold no tracker readings (/tracker/measurements or /measured_points): record the verification with the tracker node running (verify.launch.yaml)");
    }
    eprintln!(
        "identifying {} parameters from {} readings…",
        fm.param_count(),
        records.len()
    );
    let fit_options = FitOptions::default();
    let f = fit(&fm, &model.setup, &records, None, &fit_options)
        .with_context(|| format!("identifying {} from the readings", a.model.display()))?;
    let mesh = mesh_of(&records, &f);
    // the map is the machine at 20 °C: the thermal terms' coefficients say what temperature
    // adds (crates/verification reference_conditions)
    let mut conditions = at_reference_temperature(&records.records[f.used[0]].signals);
    // … and for the model's tool: readings of a reflector at other offsets identify the angular
    // errors through their Abbe arms; the map is the tool's
    conditions.tool_offset_shift = None;
    let targets = target_offsets(&records, &f, &fm);
    // said in the words and on the page: the readings carry temperatures, so the map is at 20 °C
    let at_reference = !conditions.temperatures.is_empty();
    // a tracker fixes the map only up to a rigid motion: stated with its best-fit one removed
    // (crates/estimation map_gauge), in the map, the Monte Carlo and the residual alike
    let gauge = MapGauge::RigidMotionRemoved;
    let mut map = error_map(&fm, &f.x, &mesh, &conditions)?;
    gauge.apply(&mesh, &mut map);
    let mut last = Instant::now();
    let mc = resampled_monte_carlo(
        &fm,
        &model.setup,
        &records,
        &f,
        &mesh,
        &conditions,
        gauge,
        a.trials,
        a.seed,
        &fit_options,
        |k| {
            if last.elapsed().as_secs_f64() > 1.0 || k + 1 == a.trials {
                eprint!("\rMonte Carlo: trial {}/{}", k + 1, a.trials);
                let _ = std::io::stderr().flush();
                last = Instant::now();
            }
        },
    )?;
    eprintln!();
    let points3: Vec<[f64; 3]> = mesh
        .iter()
        .map(|q| [q[0], q[1], q.get(2).copied().unwrap_or(0.0)])
        .collect();
    let cases = length_cases(&points3);
    let visits = visits(&fm, &records, &f, &mesh);
    // the length test with one target (ISO 10360-2 measures with one probe)
    let (length_visits, length_shift) = visits_of_one_target(&visits);
    let lengths = measured_lengths(&cases, &length_visits, &mc.sd_fitted, 3, mpe);
    let before: Vec<f64> = map.iter().map(|e| e.norm()).collect();
    let (before_mean, before_sd) = mean_sd(&before);
    let before_max = before.iter().copied().fold(0.0, f64::max);
    let (after_mean, after_sd) = mean_sd(&mc.residual_moduli);
    // one verification's mean residual over the points varies more than a point's: the errors
    // of a refitted map are correlated across points; its 95th percentile over the trials is
    // what one compensation may leave
    let mut trial_means: Vec<f64> = mc
        .residual_moduli
        .chunks(mesh.len())
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect();
    trial_means.sort_by(f64::total_cmp);
    let trial_p95 = trial_means
        [((trial_means.len() as f64 * 0.95).ceil() as usize).clamp(1, trial_means.len()) - 1];
    let u_point: Vec<f64> = mc.sd_fitted.iter().map(|s| s.norm()).collect();
    // the budget (seed 001 eq. 3.4), per coordinate
    // in the tracker's frame a reading's length is its range; points already in the machine
    // frame (the tracker node's /measured_points) do not carry it: --tracker-range, or 2 m said
    let (mean_range, range_source) = match (&records.frame, a.tracker_range) {
        (metrocell_estimation::RecordFrame::Instrument(_), _) => (
            records.records.iter().map(|r| r.measured.norm()).sum::<f64>() / records.len() as f64,
            "the readings' mean range".to_string(),
        ),
        (_, Some(r)) => (r, "--tracker-range".to_string()),
        (_, None) => (2.0, "2 m assumed: the points are in the machine frame and carry no range (give --tracker-range)".to_string()),
    };
    let u_cal = a.tracker_u_per_metre * mean_range;
    let u_p = (mc.residual_moduli.iter().map(|v| v * v).sum::<f64>()
        / mc.residual_moduli.len().max(1) as f64
        / 3.0)
        .sqrt();
    let u_b = standard_uncertainty_of_mean(u_p, mc.trials - mc.failed);
    let temps: Vec<f64> = records
        .records
        .iter()
        .flat_map(|r| r.signals.temperatures.values().copied())
        .collect();
    let (dt, dt_source) = if temps.is_empty() {
        (1.0, "no temperatures recorded: ±1 K from 20 °C assumed")
    } else {
        (
            temps.iter().map(|t| (t - 20.0).abs()).fold(0.0, f64::max),
            "the largest recorded distance from 20 °C",
        )
    };
    let diagonal = {
        let lo = points3.iter().fold([f64::MAX; 3], |m, p| {
            [m[0].min(p[0]), m[1].min(p[1]), m[2].min(p[2])]
        });
        let hi = points3.iter().fold([f64::MIN; 3], |m, p| {
            [m[0].max(p[0]), m[1].max(p[1]), m[2].max(p[2])]
        });
        Vector3::new(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]).norm()
    };
    let u_w = thermal_expansion_uncertainty(a.alpha_u, dt, diagonal);
    let budget_note = format!(
        "Range {:.2} m: {range_source}. Temperature {:.2} K from 20 °C: {dt_source}.",
        mean_range, dt
    );
    let budget = Budget::iso_15530_3(u_cal, u_p, u_b, u_w, 2.0);

    // words
    let mut lines = vec![
        format!(
            "verification of {} from {} readings at {} mesh points ({} visits); χ²/dof {:.3}",
            model.raw.name,
            f.used.len(),
            mesh.len(),
            visits.len(),
            f.chi2_per_dof
        ),
        format!(
            "volumetric error as the machine is{}: {:.2} ± {:.2} µm (mean ± SD over the points), largest {:.2} µm",
            if at_reference { " at 20 °C" } else { "" },
            before_mean * 1e6,
            before_sd * 1e6,
            before_max * 1e6
        ),
        format!(
            "after compensation with the identified map (Monte Carlo, {} trials{}): residual {:.2} ± {:.2} µm; one verification's mean residual over the points below {:.2} µm in 95 % of trials",
            mc.trials - mc.failed,
            if mc.failed > 0 { format!(", {} failed", mc.failed) } else { String::new() },
            after_mean * 1e6,
            after_sd * 1e6,
            trial_p95 * 1e6
        ),
        format!(
            "identified map's standard uncertainty (k = 1): {:.2} µm mean, {:.2} µm largest over the points",
            u_point.iter().sum::<f64>() / u_point.len() as f64 * 1e6,
            u_point.iter().copied().fold(0.0, f64::max) * 1e6
        ),
        format!(
            "ISO/TS 15530-3 budget: U = {:.2} µm (k = 2) per coordinate; u_cal {:.2}, u_p {:.2}, u_b {:.3}, u_w {:.2} µm",
            budget.expanded() * 1e6,
            u_cal * 1e6,
            u_p * 1e6,
            u_b * 1e6,
            u_w * 1e6
        ),
    ];
    let mm =
        |v: &Vector3<f64>| format!("({:.1}, {:.1}, {:.1}) mm", v.x * 1e3, v.y * 1e3, v.z * 1e3);
    let tool = fm.machine.tool_offset;
    if targets.len() > 1 {
        lines.push(format!(
            "{} targets (tool offsets {}): their Abbe arms separate the angular errors from straightness; the map is for the model's tool offset {}; the length test uses the target at {}",
            targets.len(),
            targets.iter().map(|(t, n)| format!("{} × {n}", mm(t))).collect::<Vec<_>>().join(", "),
            mm(&tool),
            mm(&(tool + length_shift))
        ));
    } else if let Some((t, _)) = targets.first().filter(|(t, _)| (t - tool).norm() > 1e-6) {
        lines.push(format!(
            "the readings' target is at tool offset {}, the model's tool at {}: the map is the model's tool's",
            mm(t),
            mm(&tool)
        ));
    }
    // χ²/dof of honest data is 1 ± √(2/dof): beyond 4 of those the readings disagree with
    // the model and their stated noise
    let dof = (3 * f.used.len())
        .saturating_sub(f.parameters.iter().filter(|p| p.free).count())
        .max(1);
    let chi2_limit = 1.0 + 4.0 * (2.0 / dof as f64).sqrt();
    if f.chi2_per_dof > chi2_limit {
        lines.push(format!("warning: χ²/dof {:.3} is beyond what the stated noise gives ({:.3} at most, {dof} degrees of freedom): the model lacks physics (run `metrocell diagnose` on these bags) or the readings are noisier than stated; the Monte Carlo sees only the stated noise, so the uncertainties above are too small", f.chi2_per_dof, chi2_limit));
    }
    if !f.held.is_empty() {
        lines.push(format!(
            "not identifiable from these readings, held at their start (conventions, not estimates): {}",
            f.held.iter().map(|h| h.name.as_str()).collect::<Vec<_>>().join(", ")
        ));
        // an angular error whose Abbe lever the readings never change (an axis that carries no
        // other, the reflector at one tool offset) moves the reflector as a straightness does
        let angular: Vec<&str> = f
            .held
            .iter()
            .filter(|h| h.name.starts_with("angular[") && !h.name.ends_with(".c0"))
            .map(|h| h.name.as_str())
            .collect();
        if !angular.is_empty() && targets.len() < 2 {
            lines.push(format!(
                "  {} angular coefficient(s) are not separable from straightness with the reflector at one tool offset (their Abbe lever does not change over the mesh): the map holds for the reflector's offset; separating them needs the reflector at other tool offsets (e.g. 150 mm along X and along Z, recorded on /machine/tool_offset or bag import's tool_offset.* columns)",
                angular.len()
            ));
        }
    }
    let reps = lengths.iter().map(|l| l.repetition).max().unwrap_or(0);
    let n_dir: std::collections::BTreeSet<&str> =
        cases.iter().map(|c| c.direction.as_str()).collect();
    lines.push(format!(
        "length test: {} lengths in {} directions × {} repetition(s) = {} measurements{}",
        cases.len(),
        n_dir.len(),
        reps,
        lengths.len(),
        if lengths.len() < 105 {
            " (fewer than ISO 10360-2's 105: the mesh or the visits hold no more)"
        } else {
            ""
        }
    ));
    match mpe {
        Some(_) => {
            for (when, pick) in [("as the machine is", 0), ("compensated", 1)] {
                let d: Vec<Decision> = lengths
                    .iter()
                    .filter_map(|l| {
                        if pick == 0 {
                            l.decision_before
                        } else {
                            l.decision_after
                        }
                    })
                    .collect();
                let count = |x: Decision| d.iter().filter(|v| **v == x).count();
                lines.push(format!(
                    "  {when}: {} conform, {} do not, {} not proven either way — {}",
                    count(Decision::Conforms),
                    count(Decision::DoesNotConform),
                    count(Decision::NotProven),
                    if count(Decision::Conforms) == d.len() {
                        "the machine conforms to the MPE"
                    } else if count(Decision::DoesNotConform) > 0 {
                        "the machine does not conform to the MPE"
                    } else {
                        "conformance not proven (measurements within U of the MPE)"
                    }
                ));
            }
        }
        None => lines.push(
            "  no MPE given (--mpe-a/--mpe-k/--mpe-b): the length errors are reported, not judged"
                .into(),
        ),
    }

    // files: the page, the map, the numbers
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("cannot create {}", a.output.display()))?;
    let mut csv = String::from("point,x_mm,y_mm,z_mm,ex_um,ey_um,ez_um,e_um,ux_um,uy_um,uz_um\n");
    for (k, (q, (e, u))) in mesh.iter().zip(map.iter().zip(&mc.sd_fitted)).enumerate() {
        let _ = writeln!(
            csv,
            "{k},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}",
            q[0] * 1e3,
            q[1] * 1e3,
            q.get(2).copied().unwrap_or(0.0) * 1e3,
            e.x * 1e6,
            e.y * 1e6,
            e.z * 1e6,
            e.norm() * 1e6,
            u.x * 1e6,
            u.y * 1e6,
            u.z * 1e6
        );
    }
    std::fs::write(a.output.join("map.csv"), csv)?;
    let json = serde_json::json!({
        "bags": a.bags.iter().map(|b| b.display().to_string()).collect::<Vec<_>>(),
        "model": a.model.display().to_string(),
        "readings": f.used.len(),
        "mesh_points": mesh.len(),
        "visits": visits.len(),
        "chi2_per_dof": f.chi2_per_dof,
        "held": f.held.iter().map(|h| h.name.clone()).collect::<Vec<_>>(),
        // every parameter as identified (SI; sigma null where fixed or held)
        "parameters": f.parameters.iter().map(|p| serde_json::json!({
            "name": p.name, "value": p.value, "sigma": p.sigma, "unit": p.unit, "free": p.free,
            "at_bound": p.at_bound.is_some(),
        })).collect::<Vec<_>>(),
        "volumetric_error_um": {"mean": before_mean * 1e6, "sd": before_sd * 1e6, "max": before_max * 1e6},
        "residual_after_um": {"mean": after_mean * 1e6, "sd": after_sd * 1e6, "trial_mean_p95": trial_p95 * 1e6},
        "monte_carlo": {"trials": mc.trials, "failed": mc.failed, "seed": a.seed},
        "budget_um": {"u_cal": u_cal * 1e6, "u_p": u_p * 1e6, "u_b": u_b * 1e6, "u_w": u_w * 1e6,
                      "combined": budget.combined() * 1e6, "expanded_k2": budget.expanded() * 1e6},
        "length_test": lengths.iter().map(|l| serde_json::json!({
            "direction": l.case.direction, "nominal_mm": l.case.nominal * 1e3, "repetition": l.repetition,
            "error_before_um": l.error_before * 1e6, "u_before_um": l.u_before * 1e6,
            "error_after_um": l.error_after * 1e6, "u_after_um": l.u_after * 1e6,
            "mpe_um": mpe.map(|m| m.at(l.case.nominal) * 1e6),
            "decision_before": l.decision_before.map(|d| d.in_words()),
            "decision_after": l.decision_after.map(|d| d.in_words()),
        })).collect::<Vec<_>>(),
    });
    std::fs::write(
        a.output.join("verification.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let page = page(
        &a,
        &model,
        &fm,
        &f,
        &records,
        &lines,
        &map,
        at_reference,
        &mc,
        &lengths,
        mpe,
        &budget,
        &budget_note,
        &extras,
    )?;
    for l in &lines {
        println!("{l}");
    }
    println!(
        "report: {} ({:.1} s)",
        page.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(0)
}

#[allow(clippy::too_many_arguments)]
fn page(
    a: &ReportArgs,
    model: &CellModel,
    fm: &metrocell_model::ForwardModel,
    f: &metrocell_estimation::Fit,
    records: &metrocell_estimation::RecordSet,
    lines: &[String],
    map: &[Vector3<f64>],
    at_reference: bool,
    mc: &metrocell_estimation::volumetric_monte_carlo::VolumetricMonteCarlo,
    lengths: &[metrocell_verification::measured_lengths::MeasuredLength],
    mpe: Option<Mpe>,
    budget: &Budget,
    budget_note: &str,
    extras: &[(String, String, Table)],
) -> Result<PathBuf> {
    let mut r = Report::new(&format!("Volumetric verification of {}", model.raw.name));
    let command = format!(
        "metrocell verify report --model {} {} -o {} --trials {} --seed {}",
        a.model.display(),
        a.bags
            .iter()
            .map(|b| b.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        a.output.display(),
        a.trials,
        a.seed
    );
    r.section("Summary")
        .paragraph("Signed off from the recordings named in the command below; every figure on this page is computed from them.")
        .preformatted(&command)
        .preformatted(&lines.join("\n"));
    let idx: Vec<(f64, f64)> = map
        .iter()
        .enumerate()
        .map(|(k, e)| (k as f64, e.norm() * 1e6))
        .collect();
    let band: Vec<(f64, f64)> = map
        .iter()
        .zip(&mc.sd_fitted)
        .map(|(e, u)| {
            (
                (e.norm() - 2.0 * u.norm()).max(0.0) * 1e6,
                (e.norm() + 2.0 * u.norm()) * 1e6,
            )
        })
        .collect();
    let per_point: Vec<f64> = mc.residual_moduli.iter().map(|v| v * 1e6).collect();
    r.section("Volumetric error")
        .paragraph(&format!("|e| at each mesh point as the machine is (the identified map, ± 2u from the Monte Carlo), and the distribution of the residual error after compensating with it (Monte Carlo: generating − refitted map at every point of every trial).{} The map is stated with its best-fit rigid motion over the mesh removed: a tracker placed beside the machine fixes it only up to one, and which one a fit gives depends on the parameters it held, not on the machine.", if at_reference { " The map is the machine at 20 °C (ISO 1) at every temperature sensor: the thermal terms' coefficients (parameters below) say what temperature adds." } else { "" }))
        .figure(
            "volumetric_before",
            "Volumetric error at each mesh point, ± 2u",
            SeriesPlot::new("Volumetric error as the machine is", "mesh point", "|e| [µm]")
                .series(Series::new("|e|", idx).band(band).markers())
                .svg()?,
        )
        .figure(
            "residual_after",
            "Residual volumetric error after compensation (Monte Carlo)",
            HistogramPlot::new("Residual after compensation", "|residual| [µm]", 40)
                .sample("all points, all trials", per_point)
                .svg()?,
        );
    let functions = axis_error_functions(
        fm,
        &f.x,
        f.covariance.as_ref(),
        &records.records[f.used[0]].signals,
        41,
    )?;
    let sec = r.section("Error functions");
    sec.paragraph("The identified error along each axis (the other axes mid-travel), ± 2u from the identification's covariance.");
    for func in &functions {
        let axis = ["x", "y", "z"][func.axis];
        sec.figure(
            &format!("error_{axis}"),
            &format!("Error functions along {axis}, ± 2u"),
            crate::calibrate::report::error_function_plot(func)?,
        );
    }
    let bt = crate::calibrate::report::budget_table(budget);
    r.section("Uncertainty budget (ISO/TS 15530-3)")
        .paragraph(&format!("U = k·√(u_cal² + u_p² + u_b² + u_w²), seed 001 eq. 3.4, per coordinate. u_cal: the tracker's calibration ({} per metre) at the range; u_p: the Monte Carlo's residual; u_b: its systematic part σ/√n; u_w: the expansion coefficient's uncertainty × the temperature's distance from 20 °C × the mesh's diagonal. {budget_note}", metrocell_estimation::fit_summary::value_with_sigma(a.tracker_u_per_metre, None, "m/m")))
        .table(bt);
    let mut lt = Table::new(&[
        "direction",
        "L [mm]",
        "rep.",
        "E as is [µm]",
        "U [µm]",
        "E compensated [µm]",
        "U [µm]",
        "MPE [µm]",
        "decision (compensated)",
    ]);
    for l in lengths {
        lt.push(vec![
            l.case.direction.clone(),
            format!("{:.1}", l.case.nominal * 1e3),
            l.repetition.to_string(),
            format!("{:.2}", l.error_before * 1e6),
            format!("{:.2}", l.u_before * 1e6),
            format!("{:.2}", l.error_after * 1e6),
            format!("{:.2}", l.u_after * 1e6),
            mpe.map(|m| format!("{:.2}", m.at(l.case.nominal) * 1e6))
                .unwrap_or_else(|| "—".into()),
            l.decision_after
                .map(|d| d.in_words().to_string())
                .unwrap_or_else(|| "—".into()),
        ]);
    }
    r.section("Length test (ISO 10360-2 manner)")
        .paragraph("Lengths between mesh points along the three axes and the space diagonals, from each visit's mean measured point (registered tracker): E = measured − commanded length, as the machine is and with the identified map compensated. U (k = 2) from the readings' covariance and, compensated, the map's u (points taken as independent: conservative). Decisions by ISO 14253-1: conforms when |E| + U ≤ MPE, does not when |E| − U > MPE.")
        .table(lt);
    for (heading, text, table) in extras {
        r.section(heading).paragraph(text).table(table.clone());
    }
    let mut pt = Table::new(&["parameter", "value ± u (k = 1)", "status"]);
    for p in &f.parameters {
        let status = if p.at_bound.is_some() {
            "ended on a bound of its possible range (no interior uncertainty)".to_string()
        } else if p.free {
            "identified".to_string()
        } else if let Some(h) = f.held.iter().find(|h| h.name == p.name) {
            format!("held at its start: {}", h.combination)
        } else {
            "fixed by the model file".to_string()
        };
        pt.push(vec![
            p.name.clone(),
            value_with_sigma(p.value, p.sigma, p.unit),
            status,
        ]);
    }
    r.section("Identified parameters")
        .table(pt)
        .preformatted(&summary_lines(f, records).join("\n"));
    Ok(r.write_to(&a.output)?)
}

/// The checks a metrologist signs with the verification: the probe tip (from its sphere
/// centres) and a hole plate (from `verify plate --json`), as page sections.
fn extra_checks(a: &ReportArgs) -> Result<Vec<(String, String, Table)>> {
    let mut out = vec![];
    if let Some(path) = &a.probe_tip {
        let (angles, centres) = super::probe_tip_command::read_centres(path)?;
        let c = metrocell_verification::probe_tip::probe_tip_check(&angles, &centres)
            .with_context(|| {
                format!(
                    "{}: the probe-tip check needs 8 or more angles",
                    path.display()
                )
            })?;
        let mut t = Table::new(&["quantity", "X", "Y", "Z"]);
        t.push(vec![
            "range [mm]".into(),
            format!("{:.3}", c.range.x * 1e3),
            format!("{:.3}", c.range.y * 1e3),
            format!("{:.3}", c.range.z * 1e3),
        ]);
        t.push(vec![
            "repeatability (4σ) [mm]".into(),
            format!("{:.3}", c.repeatability.x * 1e3),
            format!("{:.3}", c.repeatability.y * 1e3),
            format!("{:.3}", c.repeatability.z * 1e3),
        ]);
        let h = |x: &metrocell_verification::probe_tip::Harmonic| {
            format!(
                "{:.1} ± {:.1} µm{}",
                x.amplitude * 1e6,
                x.sigma * 1e6,
                if x.significant() {
                    " (significant)"
                } else {
                    " (not significant)"
                }
            )
        };
        t.push(vec![
            "tip eccentricity (1 per turn)".into(),
            h(&c.eccentricity),
            String::new(),
            String::new(),
        ]);
        t.push(vec![
            "three-lobe pattern (3 per turn)".into(),
            h(&c.three_lobe),
            String::new(),
            String::new(),
        ]);
        out.push(("Probe-tip check".to_string(), format!("A sphere measured with the head turned in {} steps ({}), as the thesis's Tables 5.3/5.4.", angles.len(), path.display()), t));
    }
    if let Some(path) = &a.plate {
        let j: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?,
        )
        .with_context(|| {
            format!(
                "{}: not the JSON `verify plate --json` writes",
                path.display()
            )
        })?;
        let sq = &j["squareness_mrad"];
        let (Some(v), Some(u), Some(pct)) = (
            sq["value"].as_f64(),
            sq["sigma"].as_f64(),
            j["compensated_percent"].as_f64(),
        ) else {
            bail!("{}: not the JSON `verify plate --json` writes (no squareness_mrad, compensated_percent)", path.display());
        };
        let mut t = Table::new(&["quantity", "value"]);
        t.push(vec![
            "xWy (squareness of X and Y)".into(),
            format!("{v:.5} ± {u:.5} mrad (k = 1)"),
        ]);
        t.push(vec![
            "compensated by the six components".into(),
            format!("{pct:.2} % (the thesis: 94.39 %)"),
        ]);
        out.push((
            "Hole plate (XY)".to_string(),
            format!(
                "A calibrated plate measured in the XY plane ({}).",
                path.display()
            ),
            t,
        ));
    }
    Ok(out)
}
