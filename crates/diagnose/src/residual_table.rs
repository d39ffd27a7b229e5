//! The per-record residual table (`metrocell diagnose --residuals FILE.csv`): what other tools
//! (the concealed-effect suite's PySINDy baseline, a spreadsheet) need to look for structure
//! themselves — per record its time, channel and point, where it was taken, the residual after
//! the *declared* fit along the workpiece axes with its stated σ, and every signal it carries.
//!
//! Columns (SI: s, m, m/s, °C, Pa, %RH, N): `time`, `channel`, `point_id`, `position_x|y|z`
//! (commanded axis positions, or the nominal tool point), `residual_x|y|z` (measured −
//! predicted after the declared fit), `sigma_x|y|z`, `approach_x|y|z` (±1), `velocity_x|y|z`,
//! `temperature.<sensor>` (one per sensor every record has), `air_temperature`, `air_pressure`,
//! `air_humidity`, `time_since_power_on`, `load_x|y|z`. A signal a record lacks is empty.

use std::collections::BTreeSet;
use std::fmt::Write;

use crate::pipeline::Diagnosis;

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.9e}")).unwrap_or_default()
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The table as CSV text.
pub fn residuals_csv(d: &Diagnosis) -> String {
    let records = &d.records;
    let sensors: BTreeSet<String> = records
        .first()
        .map(|r| {
            r.signals
                .temperatures
                .keys()
                .filter(|k| {
                    records
                        .iter()
                        .all(|x| x.signals.temperatures.contains_key(*k))
                })
                .cloned()
                .collect()
        })
        .unwrap_or_default();
    let mut out = String::from("time,channel,point_id,position_x,position_y,position_z,residual_x,residual_y,residual_z,sigma_x,sigma_y,sigma_z,approach_x,approach_y,approach_z,velocity_x,velocity_y,velocity_z");
    for s in &sensors {
        let _ = write!(out, ",temperature.{}", quote(s));
    }
    out.push_str(
        ",air_temperature,air_pressure,air_humidity,time_since_power_on,load_x,load_y,load_z\n",
    );
    for (i, r) in records.iter().enumerate() {
        let p = d.plots.position[i];
        let e = d.plots.before[i];
        let s = d.sigma_workpiece[i];
        let sig = &r.signals;
        let _ = write!(
            out,
            "{:.6},{},{},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e}",
            r.time,
            quote(&r.channel),
            quote(&r.point_id),
            p.x,
            p.y,
            p.z,
            e.x,
            e.y,
            e.z,
            s.x,
            s.y,
            s.z
        );
        for k in 0..3 {
            let _ = write!(out, ",{}", opt(sig.approach_direction[k]));
        }
        for k in 0..3 {
            let _ = write!(out, ",{}", opt(sig.axis_velocity[k]));
        }
        for name in &sensors {
            let _ = write!(out, ",{}", opt(sig.temperatures.get(name).copied()));
        }
        let load = sig.load_force;
        let _ = writeln!(
            out,
            ",{},{},{},{},{},{},{}",
            opt(sig.air_temperature),
            opt(sig.air_pressure),
            opt(sig.air_humidity),
            opt(sig.time_since_power_on),
            opt(load.map(|f| f.x)),
            opt(load.map(|f| f.y)),
            opt(load.map(|f| f.z))
        );
    }
    out
}
