//! The conditions a model is evaluated at for compensation: temperatures of the sensors its
//! thermal terms read, and the load.

use anyhow::{bail, Context};
use metrocell_physics::Signals;
use metrocell_twin::CellModel;
use nalgebra::Vector3;

/// `--temperature NAME=°C` values and `--load FX,FY,FZ` (N) as signals.
pub fn signals(temperatures: &[String], load: Option<&str>) -> anyhow::Result<Signals> {
    let mut s = Signals::default();
    for t in temperatures {
        let (name, value) = t.split_once('=').with_context(|| format!("--temperature `{t}`: expected NAME=°C, e.g. x_left=21.4"))?;
        let v: f64 = value.trim().trim_end_matches("degC").trim().parse().with_context(|| format!("--temperature `{t}`: `{value}` is not a number of °C"))?;
        if !v.is_finite() {
            bail!("--temperature `{t}`: not finite");
        }
        s.temperatures.insert(name.trim().to_string(), v);
    }
    if let Some(l) = load {
        let v: Vec<f64> = l.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().with_context(|| format!("--load `{l}`: expected FX,FY,FZ in N"))?;
        if v.len() != 3 {
            bail!("--load `{l}`: expected three numbers FX,FY,FZ in N");
        }
        s.load_force = Some(Vector3::new(v[0], v[1], v[2]));
    }
    Ok(s)
}

/// `X,Y,Z` in mm → m.
pub fn point_mm(text: &str, what: &str) -> anyhow::Result<Vector3<f64>> {
    let v: Vec<f64> = text.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().with_context(|| format!("{what} `{text}`: expected X,Y,Z in mm"))?;
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
            metrocell_physics::SignalKind::Temperature(n) | metrocell_physics::SignalKind::TemperatureHistory(n) => Some(n),
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
            bail!("--temperature {name}=…: the model's terms read no sensor `{name}`; they read {}", read.join(", "));
        }
    }
    Ok(())
}

/// Why a machine family gets no X Y Z compensation (`None`: cartesian and delta machines do).
pub fn not_xyz_family(model: &CellModel) -> Option<&'static str> {
    match model.machine.kinematics {
        metrocell_model::MachineKinematics::Cartesian(_) | metrocell_model::MachineKinematics::Delta(_) => None,
        metrocell_model::MachineKinematics::FiveAxis(_) => Some("five_axis"),
        metrocell_model::MachineKinematics::SerialArm(_) => Some("serial_arm"),
    }
}
