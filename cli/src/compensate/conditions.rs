//! The conditions a model is evaluated at for compensation: temperatures of the sensors its
//! thermal terms read, the temperature history a lagged term reads, and the load.
//!
//! A lagged term (`thermal_growth` with `lag: true`, as `diagnose` writes it) reads its
//! sensor's history filtered by its time constant. It comes from a recording
//! (`--temperatures-from BAG`, the `/temperature/<sensor>` topics, at `--at-time`), or, without
//! one, a steady state is assumed — the structure has settled at the `--temperature` given — and
//! the output says so.

use std::path::Path;
use std::sync::Arc;

use anyhow::{bail, Context};
use metrocell_model::SignalsBuilderOptions;
use metrocell_model_file::CellModel;
use metrocell_physics::{SignalKind, Signals, TemperatureTimeline};
use metrocell_records::recordings::signals_from_bag;
use nalgebra::Vector3;

/// What the compensation is evaluated at, and what the output says about it.
pub struct Conditions {
    pub signals: Signals,
    /// Sentences for the output: where the temperatures came from, what was assumed.
    pub statements: Vec<String>,
}

/// The command-line options the conditions come from.
pub struct ConditionOptions<'a> {
    pub temperatures: &'a [String],
    pub load: Option<&'a str>,
    pub history: Option<&'a Path>,
    pub at_time: Option<&'a str>,
}

/// A lagged term of the model: (label, sensor, τ s).
fn lagged_terms(model: &CellModel) -> Vec<(String, String, f64)> {
    let mut out = Vec::new();
    for t in &model.machine_terms.terms {
        for s in t.term.signals() {
            if let SignalKind::TemperatureHistory(sensor) = s {
                let tau = t
                    .term
                    .params()
                    .iter()
                    .zip(&t.params)
                    .find(|(p, _)| p.name == "time_constant")
                    .map(|(_, v)| *v)
                    .unwrap_or(f64::NAN);
                out.push((t.term.label(), sensor, tau));
            }
        }
    }
    out
}

/// The conditions of `model`'s compensation (module docs).
pub fn conditions(model: &CellModel, o: &ConditionOptions) -> anyhow::Result<Conditions> {
    let mut s = signals(o.temperatures, o.load)?;
    // the names given by hand must be sensors the model reads (a recording's may hold others)
    check_sensor_names(&s, model)?;
    let mut statements = Vec::new();
    let lagged = lagged_terms(model);
    if o.at_time.is_some() && o.history.is_none() {
        bail!("--at-time is a time in the recording of --temperatures-from BAG; give the bag too");
    }
    if let Some(bag) = o.history {
        statements.extend(from_recording(model, bag, o, &lagged, &mut s)?);
        return Ok(Conditions {
            signals: s,
            statements,
        });
    }
    if lagged.is_empty() {
        return Ok(Conditions {
            signals: s,
            statements,
        });
    }
    // steady state: each lagged sensor's history is its one given temperature
    let timeline = TemperatureTimeline::new();
    for (label, sensor, tau) in &lagged {
        let Some(&v) = s.temperatures.get(sensor) else {
            bail!(
                "{label} lags temperature sensor `{sensor}` by τ = {:.1} min and needs its history: give --temperatures-from BAG (a recording with /temperature/{sensor}; --at-time picks the instant, default its end), or --temperature {sensor}=°C to assume a steady state (the structure settled at that temperature)",
                tau / 60.0
            );
        };
        if !timeline.contains(sensor) {
            timeline.push(sensor, 0.0, v).map_err(anyhow::Error::msg)?;
        }
        statements.push(format!(
            "steady state assumed: {label} lags sensor `{sensor}` by τ = {:.1} min and no temperature history was given (--temperatures-from BAG), so the structure is taken as settled at {sensor}'s {v:.2} °C",
            tau / 60.0
        ));
    }
    s.timeline = Some(Arc::new(timeline));
    s.time = Some(0.0);
    Ok(Conditions {
        signals: s,
        statements,
    })
}

/// Temperatures, their history and the load from a recording at `--at-time` (seconds after its
/// first temperature sample; default its last); values given on the command line win.
fn from_recording(
    model: &CellModel,
    bag: &Path,
    o: &ConditionOptions,
    lagged: &[(String, String, f64)],
    s: &mut Signals,
) -> anyhow::Result<Vec<String>> {
    let (builder, _) = signals_from_bag(bag, &model.machine, &SignalsBuilderOptions::default())
        .with_context(|| format!("--temperatures-from {}", bag.display()))?;
    let timeline = builder.timeline().clone();
    let spans: Vec<(f64, f64)> = timeline
        .sensors()
        .iter()
        .filter_map(|n| timeline.time_span(n))
        .collect();
    if spans.is_empty() {
        bail!("--temperatures-from {}: the recording has no temperature topics (/temperature/<sensor>, sensor_msgs/Temperature)", bag.display());
    }
    let first = spans.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    let last = spans.iter().map(|s| s.1).fold(f64::NEG_INFINITY, f64::max);
    let after = match o.at_time {
        Some(t) => {
            let v = metrocell_physics::units::parse_quantity(t, "s").map_err(|e| anyhow::anyhow!("--at-time `{t}`: {e:?}; give a time after the recording's first temperature sample, e.g. 2h or 5400"))?;
            if !(0.0..=last - first).contains(&v) {
                bail!("--at-time `{t}`: the recording's temperatures span 0 to {:.0} s ({:.2} h); give a time in it", last - first, (last - first) / 3600.0);
            }
            v
        }
        None => last - first,
    };
    let at = first + after;
    let recorded = builder.signals_at((at * 1e9).round() as i64);
    for (label, sensor, _) in lagged {
        if !timeline.contains(sensor) {
            bail!("--temperatures-from {}: {label} lags sensor `{sensor}`, and the recording has no /temperature/{sensor}; recorded: {}", bag.display(), timeline.sensors().join(", "));
        }
    }
    let mut given = Vec::new();
    for (name, v) in &recorded.temperatures {
        match s.temperatures.get(name) {
            Some(mine) => given.push(format!("{name} {mine:.2} °C (given; recorded {v:.2})")),
            None => {
                s.temperatures.insert(name.clone(), *v);
                given.push(format!("{name} {v:.2} °C"));
            }
        }
    }
    if s.load_force.is_none() {
        s.load_force = recorded.load_force;
    }
    s.time = recorded.time;
    s.timeline = recorded.timeline.clone();
    let mut out = vec![format!(
        "temperatures from {} at {:.0} s after its first temperature sample ({:.2} h): {}",
        bag.display(),
        after,
        after / 3600.0,
        given.join(", ")
    )];
    for (label, sensor, tau) in lagged {
        if let Ok((tf, _)) = s.lagged_temperature(label.as_str(), sensor, *tau) {
            out.push(format!("{label} lags sensor `{sensor}` by τ = {:.1} min: its structure is at {tf:.2} °C (the recorded history filtered)", tau / 60.0));
        }
    }
    Ok(out)
}

/// `--temperature NAME=°C` values and `--load FX,FY,FZ` (N) as signals.
pub fn signals(temperatures: &[String], load: Option<&str>) -> anyhow::Result<Signals> {
    let mut s = Signals::default();
    for t in temperatures {
        let (name, value) = t
            .split_once('=')
            .with_context(|| format!("--temperature `{t}`: expected NAME=°C, e.g. x_left=21.4"))?;
        let v: f64 = value
            .trim()
            .trim_end_matches("degC")
            .trim()
            .parse()
            .with_context(|| format!("--temperature `{t}`: `{value}` is not a number of °C"))?;
        if !v.is_finite() {
            bail!("--temperature `{t}`: not finite");
        }
        s.temperatures.insert(name.trim().to_string(), v);
    }
    if let Some(l) = load {
        let v: Vec<f64> = l
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("--load `{l}`: expected FX,FY,FZ in N"))?;
        if v.len() != 3 {
            bail!("--load `{l}`: expected three numbers FX,FY,FZ in N");
        }
        s.load_force = Some(Vector3::new(v[0], v[1], v[2]));
    }
    Ok(s)
}

/// `X,Y,Z` in mm → m.
pub fn point_mm(text: &str, what: &str) -> anyhow::Result<Vector3<f64>> {
    let v: Vec<f64> = text
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("{what} `{text}`: expected X,Y,Z in mm"))?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
        bail!("{what} `{text}`: expected three finite numbers X,Y,Z in mm");
    }
    Ok(Vector3::new(v[0], v[1], v[2]) * 1e-3)
}

/// The temperature sensors the model's terms read (for the error message when one is missing).
pub fn sensors_read(model: &CellModel) -> Vec<String> {
    let mut names: Vec<String> = model
        .machine_terms
        .terms
        .iter()
        .flat_map(|t| t.term.signals())
        .filter_map(|s| match s {
            metrocell_physics::SignalKind::Temperature(n)
            | metrocell_physics::SignalKind::TemperatureHistory(n) => Some(n),
            _ => None,
        })
        .collect();
    names.sort();
    names.dedup();
    names
}

/// `--temperature NAME=…` names only sensors the model's terms read: a misspelt or foreign
/// sensor would otherwise be ignored and the compensation made at another temperature than
/// the user meant. (Whether every sensor the terms read is given is the error field's check.)
pub fn check_sensor_names(conditions: &Signals, model: &CellModel) -> anyhow::Result<()> {
    let read = sensors_read(model);
    for name in conditions.temperatures.keys() {
        if !read.contains(name) {
            if read.is_empty() {
                bail!("--temperature {name}=…: the model's terms read no temperature; leave --temperature out");
            }
            bail!(
                "--temperature {name}=…: the model's terms read no sensor `{name}`; they read {}",
                read.join(", ")
            );
        }
    }
    Ok(())
}

/// Why a machine family gets no X Y Z compensation (`None`: cartesian and delta machines do).
pub fn not_xyz_family(model: &CellModel) -> Option<&'static str> {
    match model.machine.kinematics {
        metrocell_model::MachineKinematics::Cartesian(_)
        | metrocell_model::MachineKinematics::Delta(_) => None,
        metrocell_model::MachineKinematics::FiveAxis(_) => Some("five_axis"),
        metrocell_model::MachineKinematics::SerialArm(_) => Some("serial_arm"),
    }
}
