//! The findings in a metrologist's words: each found term's parameters with their standard
//! uncertainties, where its effect lives (and which localisation findings it accounts for), the
//! evidence (the residual with the term's effect put back, against the term's signal), and one
//! sentence with the numbers in µm, mm and minutes. Also the structures no term explains, the
//! advice on what to measure next, and the summary paragraph.

use std::collections::{BTreeMap, BTreeSet};

use metrocell_estimation::{MeasurementRecord, PointResiduals};
use metrocell_model::ForwardModel;
use metrocell_physics::{configure, ConfigValue, PhysicsError, TermConfig, TermId};
use nalgebra::Vector3;

use crate::candidates::Placement;
use crate::empirical::{EmpiricalShape, FittedEmpirical};
use crate::locate::{Finding as Located, Place};
use crate::report::*;
use crate::residual::{axis_name, ResidualSample};
use crate::selection::{Family, FamilySelection};

/// A term the selection added, as it sits in the augmented model.
#[derive(Debug, Clone)]
pub struct FoundTerm {
    pub label: String,
    pub id: TermId,
    pub variant: String,
    pub placement: Placement,
    pub order: usize,
    pub config: TermConfig,
}

pub struct Inputs<'a> {
    pub model: &'a ForwardModel<'a>,
    pub x: &'a [f64],
    /// Which parameters were fitted (the findings list those).
    pub free: &'a [bool],
    pub sigmas: &'a [Option<f64>],
    pub names: &'a [String],
    pub records: &'a [MeasurementRecord],
    pub view: &'a crate::residual_view::ResidualView,
    /// Workpiece-frame residual after everything, m.
    pub after: &'a [Vector3<f64>],
    pub found: &'a [FoundTerm],
    pub located_before: &'a [Located],
    pub samples_before: &'a [ResidualSample],
    /// Each added term's (label, significance of its main parameters in σ).
    pub significance: &'a [(String, f64)],
    /// The alternatives the selection could not tell from each chosen label.
    pub alternatives: &'a BTreeMap<String, Vec<Alternative>>,
    /// Parameters (`label.param`) the final refit left on a bound of their possible range, and
    /// which (`lower`, `upper`).
    pub at_bound: &'a [(String, String)],
}

/// A finding's evidence per record: signal, residual along the evidence direction, fitted effect.
pub type EvidenceSeries = (Vec<f64>, Vec<f64>, Vec<f64>);

pub struct Built {
    pub findings: Vec<Finding>,
    /// Per finding (same order).
    pub evidence: Vec<EvidenceSeries>,
}

/// µm with one decimal.
fn um(v: f64) -> String {
    format!("{:.1}", v * 1e6)
}

fn text_option(c: &TermConfig, key: &str) -> Option<String> {
    match c.options.get(key) {
        Some(ConfigValue::Text(t)) => Some(t.clone()),
        _ => None,
    }
}

fn axis_index(name: &str) -> Option<usize> {
    match name {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

fn upper(a: &str) -> String {
    a.to_uppercase()
}

/// The parameters of a label in the augmented model: (param name, value, σ, unit).
fn params_of(inputs: &Inputs, label: &str) -> Vec<(String, f64, Option<f64>, String)> {
    let specs: Vec<_> = inputs
        .model
        .machine_terms
        .param_specs()
        .into_iter()
        .chain(inputs.model.instrument_terms.param_specs())
        .collect();
    inputs
        .names
        .iter()
        .enumerate()
        .filter(|(k, _)| inputs.free[*k])
        .filter_map(|(k, n)| {
            n.strip_prefix(&format!("{label}.")).map(|p| {
                (
                    p.to_string(),
                    inputs.x[k],
                    inputs.sigmas[k],
                    specs[k].unit.to_string(),
                )
            })
        })
        .collect()
}

/// The stacked vector with the term's amplitudes at zero (parameters whose range holds 0), so
/// the difference of predictions is the term's effect.
fn without(inputs: &Inputs, label: &str) -> Vec<f64> {
    let specs: Vec<_> = inputs
        .model
        .machine_terms
        .param_specs()
        .into_iter()
        .chain(inputs.model.instrument_terms.param_specs())
        .collect();
    let mut x = inputs.x.to_vec();
    for (k, n) in inputs.names.iter().enumerate() {
        if n.starts_with(&format!("{label}."))
            && specs[k].usual.contains(0.0)
            && specs[k].possible.contains(0.0)
        {
            x[k] = 0.0;
        }
    }
    x
}

/// Does a localisation finding's subset contain record sample `s`?
fn in_place(place: &Place, s: &ResidualSample) -> Option<bool> {
    Some(match place {
        Place::Region { axis, from, to } => s.position[*axis] >= *from && s.position[*axis] <= *to,
        Place::TimeWindow { from, to } => s.time >= *from && s.time <= *to,
        Place::Direction { axis, sign } => s.approach[*axis] == Some(*sign),
        Place::ConditionRange { name, from, to } => {
            s.condition(name).is_some_and(|v| v >= *from && v <= *to)
        }
        Place::Correlation { .. } => return None,
    })
}

/// Localisation findings the effect `c` (workpiece frame, per record) accounts for: its mean
/// over the finding's subset is at least half the finding's effect, with the same sign (the six
/// strongest).
fn accounted(located: &[Located], samples: &[ResidualSample], c: &[Vector3<f64>]) -> Vec<String> {
    let mut out = Vec::new();
    for f in located.iter().take(30) {
        let (mut sum, mut count) = (0.0, 0usize);
        let mut pairs = Vec::new();
        for (k, s) in samples.iter().enumerate() {
            if s.channel != f.channel || s.axis != f.axis {
                continue;
            }
            let i = k / 3;
            match in_place(&f.place, s) {
                Some(true) => {
                    sum += c[i][f.axis];
                    count += 1;
                }
                Some(false) => {}
                None => {
                    if let Place::Correlation { name } = &f.place {
                        if let Some(v) = s.condition(name) {
                            pairs.push((v, c[i][f.axis]));
                        }
                    }
                }
            }
        }
        let effect = if let Place::Correlation { .. } = f.place {
            if pairs.len() < 3 {
                continue;
            }
            let m = pairs.len() as f64;
            let (mv, mc) = (
                pairs.iter().map(|p| p.0).sum::<f64>() / m,
                pairs.iter().map(|p| p.1).sum::<f64>() / m,
            );
            let var = pairs.iter().map(|p| (p.0 - mv).powi(2)).sum::<f64>() / m;
            let cov = pairs.iter().map(|p| (p.0 - mv) * (p.1 - mc)).sum::<f64>() / m;
            if var > 0.0 {
                cov / var.sqrt()
            } else {
                0.0
            }
        } else if count > 0 {
            // the effect relative to the channel's mean, as localisation measures it
            sum / count as f64
        } else {
            continue;
        };
        if effect * f.effect_m > 0.0 && effect.abs() >= 0.5 * f.effect_m.abs() {
            out.push(f.describe());
            if out.len() == 6 {
                break;
            }
        }
    }
    out
}

/// Bins of (signal, residual, fitted) by quantiles of the signal.
fn bins(signal: &[f64], residual: &[f64], fitted: &[f64], sigma: &[f64]) -> Vec<EvidenceBin> {
    let n = signal.len();
    if n == 0 {
        return Vec::new();
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| signal[a].total_cmp(&signal[b]));
    let distinct: BTreeSet<u64> = signal.iter().map(|v| v.to_bits()).collect();
    let count = distinct.len().clamp(1, 12);
    let mut out = Vec::new();
    if distinct.len() <= 12 {
        // a few signal values (approach ±1, a handful of positions): one bin each
        for bits in distinct {
            let idx: Vec<usize> = (0..n).filter(|&i| signal[i].to_bits() == bits).collect();
            out.push(bin(&idx, signal, residual, fitted, sigma));
        }
        return out;
    }
    for b in 0..count {
        let idx: Vec<usize> = order[b * n / count..(b + 1) * n / count].to_vec();
        if !idx.is_empty() {
            out.push(bin(&idx, signal, residual, fitted, sigma));
        }
    }
    out
}

fn bin(
    idx: &[usize],
    signal: &[f64],
    residual: &[f64],
    fitted: &[f64],
    sigma: &[f64],
) -> EvidenceBin {
    let m = idx.len() as f64;
    let mean = |v: &[f64]| idx.iter().map(|&i| v[i]).sum::<f64>() / m;
    let r = mean(residual);
    let spread = if idx.len() > 1 {
        (idx.iter().map(|&i| (residual[i] - r).powi(2)).sum::<f64>() / (m - 1.0)).sqrt()
    } else {
        sigma[idx[0]]
    };
    EvidenceBin {
        signal: mean(signal),
        residual_m: r,
        residual_sigma_m: spread / m.sqrt(),
        fitted_m: mean(fitted),
        count: idx.len(),
    }
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    if n < 2.0 {
        return 0.0;
    }
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    if va > 0.0 && vb > 0.0 {
        cov / (va * vb).sqrt()
    } else {
        0.0
    }
}

/// The found terms as findings, largest effect first.
pub fn build(inputs: &Inputs) -> Result<Built, PhysicsError> {
    let problem = PointResiduals::new(inputs.model, inputs.records).map_err(|b| {
        PhysicsError::InvalidInput {
            what: format!("record {}", b.index),
            reason: "covariance".into(),
        }
    })?;
    let full = problem.predictions(inputs.x)?;
    let mut out: Vec<(f64, Finding, EvidenceSeries)> = Vec::new();
    for f in inputs.found {
        let bare = problem.predictions(&without(inputs, &f.label))?;
        // the term's effect on each reading, in the readings' frame
        let c_rec: Vec<Vector3<f64>> = full.iter().zip(&bare).map(|(a, b)| a - b).collect();
        out.push(finding_of(inputs, f, &c_rec));
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    let (findings, evidence) = out.into_iter().map(|(_, f, e)| (f, e)).unzip();
    Ok(Built { findings, evidence })
}

/// One found term whose effect on each reading is `c_rec`, as a finding: the RMS of its effect,
/// the finding, and its evidence per record (signal, residual with the effect put back, fitted
/// effect).
fn finding_of(
    inputs: &Inputs,
    f: &FoundTerm,
    c_rec: &[Vector3<f64>],
) -> (f64, Finding, EvidenceSeries) {
    let n = inputs.records.len();
    let c_wp: Vec<Vector3<f64>> = c_rec
        .iter()
        .enumerate()
        .map(|(i, c)| inputs.view.rotation(i) * c)
        .collect();
    let effect_rms =
        (c_wp.iter().map(|c| c.norm_squared()).sum::<f64>() / (3 * n).max(1) as f64).sqrt();
    let per_axis: Vec<f64> = (0..3)
        .map(|k| c_wp.iter().map(|c| c[k] * c[k]).sum::<f64>())
        .collect();
    let total: f64 = per_axis.iter().sum();
    let main = (0..3)
        .max_by(|&a, &b| per_axis[a].total_cmp(&per_axis[b]))
        .unwrap_or(0);
    let share = if total > 0.0 {
        100.0 * per_axis[main] / total
    } else {
        0.0
    };
    let (along, fitted, residual) = effect_put_back(inputs, f, c_rec, &c_wp, main);
    let (signal_name, unit, signal) = signal_of(f, inputs, &fitted);
    let sigma: Vec<f64> = (0..n)
        .map(|i| {
            inputs
                .view
                .workpiece_sigma(i, &inputs.records[i].covariance)[main]
        })
        .collect();
    let evidence = Evidence {
        signal: signal_name,
        unit,
        along,
        bins: bins(&signal, &residual, &fitted, &sigma),
        correlation: correlation(&residual, &fitted),
    };
    let params = params_of(inputs, &f.label);
    let unusual = unusual_values(inputs, &f.label);
    let alternatives: Vec<Alternative> = inputs
        .alternatives
        .get(&f.label)
        .cloned()
        .unwrap_or_default()
        .into_iter()
        .filter(|a| !inputs.found.iter().any(|g| g.label == a.label))
        .collect();
    let statement = with_caveats(statement(f, &params, &c_wp, main), &unusual, &alternatives);
    let significance_sigma = inputs
        .significance
        .iter()
        .find(|(l, _)| *l == f.label)
        .map(|s| s.1)
        .unwrap_or(f64::NAN);
    let finding = Finding {
        term: f.id.as_str().into(),
        label: f.label.clone(),
        variant: f.variant.clone(),
        parameters: parameter_values(inputs, &f.label, &params),
        location: location_of(inputs, &c_wp, main, share),
        evidence,
        statement,
        effect_rms_m: effect_rms,
        significance_sigma,
        unusual,
        alternatives,
    };
    (effect_rms, finding, (signal, residual, fitted))
}

/// The evidence direction and, along it, the fitted effect and the residual with the effect put
/// back: along the main workpiece axis, or a range term's along the line of sight.
fn effect_put_back(
    inputs: &Inputs,
    f: &FoundTerm,
    c_rec: &[Vector3<f64>],
    c_wp: &[Vector3<f64>],
    main: usize,
) -> (String, Vec<f64>, Vec<f64>) {
    let n = inputs.records.len();
    if f.placement == Placement::Instrument {
        let los = &inputs.view.line_of_sight;
        let rot = |i: usize| inputs.view.rotation(i);
        (
            "line of sight".into(),
            (0..n).map(|i| c_rec[i].dot(&los[i])).collect(),
            (0..n)
                .map(|i| (rot(i).transpose() * inputs.after[i] + c_rec[i]).dot(&los[i]))
                .collect(),
        )
    } else {
        (
            axis_name(main).into(),
            c_wp.iter().map(|c| c[main]).collect(),
            (0..n)
                .map(|i| inputs.after[i][main] + c_wp[i][main])
                .collect(),
        )
    }
}

/// A term's parameters as reported: value, σ (none at a bound of the possible range), unit.
fn parameter_values(
    inputs: &Inputs,
    label: &str,
    params: &[(String, f64, Option<f64>, String)],
) -> BTreeMap<String, ParameterValue> {
    params
        .iter()
        .map(|(n, v, s, u)| {
            let at_bound = inputs
                .at_bound
                .iter()
                .find(|(name, _)| *name == format!("{label}.{n}"))
                .map(|(_, side)| side.clone());
            (
                n.clone(),
                ParameterValue {
                    value: *v,
                    sigma: if at_bound.is_some() { None } else { *s },
                    unit: u.clone(),
                    at_bound,
                },
            )
        })
        .collect()
}

/// Where an effect `c_wp` lives: the channels it reaches over a fifth of its largest, where the
/// largest is, its main axis (`share` % of it along that axis), and the localisation findings
/// it accounts for.
fn location_of(inputs: &Inputs, c_wp: &[Vector3<f64>], main: usize, share: f64) -> Where {
    let n = inputs.records.len();
    let largest = (0..n)
        .max_by(|&a, &b| c_wp[a].norm().total_cmp(&c_wp[b].norm()))
        .unwrap_or(0);
    let channels: BTreeSet<String> = (0..n)
        .filter(|&i| c_wp[i].norm() > 0.2 * c_wp[largest].norm())
        .map(|i| inputs.records[i].channel.clone())
        .collect();
    let p = inputs.view.position[largest];
    let description = format!(
        "largest ({} µm) at x {:.0} mm, y {:.0} mm, z {:.0} mm ({}), t = {:.2} h into the recording; {:.0} % of the effect is along {}",
        um(c_wp[largest].norm()),
        p.x * 1e3,
        p.y * 1e3,
        p.z * 1e3,
        inputs.view.position_frame,
        (inputs.view.time[largest] - inputs.view.time.iter().cloned().fold(f64::INFINITY, f64::min)) / 3600.0,
        share,
        axis_name(main)
    );
    Where {
        channels: channels.into_iter().collect(),
        axis: axis_name(main).into(),
        description,
        located: accounted(inputs.located_before, inputs.samples_before, c_wp),
    }
}

/// A finding's statement with its unusual values and the alternatives the recording cannot
/// tell it from.
fn with_caveats(mut statement: String, unusual: &[String], alternatives: &[Alternative]) -> String {
    if !unusual.is_empty() {
        statement.push_str(&format!(" — unusual: {}", unusual.join("; ")));
    }
    if !alternatives.is_empty() {
        statement.push_str(&format!(
            " — this recording cannot tell it from {} ({})",
            alternatives
                .iter()
                .map(|a| a.label.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            alternatives
                .iter()
                .map(|a| a.separated_by.as_str())
                .collect::<BTreeSet<_>>()
                .into_iter()
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    statement
}

/// The signal a term's evidence is plotted against.
fn signal_of(f: &FoundTerm, inputs: &Inputs, fitted: &[f64]) -> (String, String, Vec<f64>) {
    let records = inputs.records;
    let axis = text_option(&f.config, "axis").or_else(|| text_option(&f.config, "extension_axis"));
    let position = |k: usize| {
        records
            .iter()
            .map(|r| r.signals.axis_position[k].unwrap_or(f64::NAN))
            .collect::<Vec<f64>>()
    };
    match f.id {
        TermId::Positioning
        | TermId::Straightness
        | TermId::PitchCyclic
        | TermId::Angular
        | TermId::Compliance => {
            let k = axis.as_deref().and_then(axis_index).unwrap_or(0);
            (
                format!("{} position", axis_name(k)),
                "m".into(),
                position(k),
            )
        }
        TermId::Squareness => {
            let pair = text_option(&f.config, "pair").unwrap_or_default();
            let k = pair.get(1..2).and_then(axis_index).unwrap_or(1);
            (
                format!("{} position", axis_name(k)),
                "m".into(),
                position(k),
            )
        }
        TermId::Backlash => {
            let k = axis.as_deref().and_then(axis_index).unwrap_or(0);
            (
                format!(
                    "direction of approach of {} (+1 moving +, −1 moving −)",
                    axis_name(k)
                ),
                "1".into(),
                records
                    .iter()
                    .map(|r| r.signals.approach_direction[k].unwrap_or(0.0))
                    .collect(),
            )
        }
        TermId::TrackerWarmup => (
            "time since the tracker was powered on".into(),
            "s".into(),
            records
                .iter()
                .map(|r| r.signals.time_since_power_on.unwrap_or(f64::NAN))
                .collect(),
        ),
        TermId::Refraction => (
            "measured range".into(),
            "m".into(),
            inputs
                .view
                .line_of_sight
                .iter()
                .zip(records)
                .map(|(_, r)| r.measured.norm())
                .collect(),
        ),
        TermId::TimeOffset => (
            "speed".into(),
            "m/s".into(),
            records
                .iter()
                .map(|r| {
                    r.signals
                        .axis_velocity
                        .iter()
                        .map(|v| v.unwrap_or(0.0).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect(),
        ),
        TermId::ThermalScale | TermId::ThermalGrowth => {
            // the term's own signal: its prediction at unit coefficient, along its direction
            let mut unit_config = f.config.clone();
            let first = if f.id == TermId::ThermalScale {
                "alpha"
            } else {
                "coefficient"
            };
            unit_config
                .params
                .insert(first.into(), ConfigValue::Number(1.0));
            let values = configure(&unit_config).ok().map(|t| {
                records
                    .iter()
                    .map(|r| {
                        // one-axis directions: the signed component is the sum
                        t.term
                            .predict(&t.params, &r.signals)
                            .map(|p| p.value.iter().sum::<f64>())
                            .unwrap_or(f64::NAN)
                    })
                    .collect()
            });
            let name = if f.id == TermId::ThermalScale {
                "axis position × (temperature − reference)"
            } else {
                "temperature − reference (lagged where the term lags)"
            };
            (
                name.into(),
                if f.id == TermId::ThermalScale {
                    "m·K".into()
                } else {
                    "K".into()
                },
                values.unwrap_or_else(|| fitted.to_vec()),
            )
        }
        _ => ("fitted effect".into(), "m".into(), fitted.to_vec()),
    }
}

/// Material whose expansion coefficient range the fitted α (±2σ) overlaps, naming the one that
/// holds the value.
fn material(alpha: f64, sigma: f64) -> Option<&'static str> {
    const MATERIALS: [(f64, f64, &str); 5] = [
        (-0.5e-6, 2.0e-6, "a low-expansion (Invar, Zerodur) scale"),
        (5.5e-6, 9.5e-6, "a glass scale"),
        (9.5e-6, 13.5e-6, "steel"),
        (15.0e-6, 18.5e-6, "brass or stainless steel"),
        (21.0e-6, 25.5e-6, "aluminium"),
    ];
    MATERIALS
        .iter()
        .find(|(lo, hi, _)| {
            alpha + 2.0 * sigma >= *lo && alpha - 2.0 * sigma <= *hi && alpha >= lo - 2.0 * sigma
        })
        .map(|m| m.2)
}

/// Value ± σ in a display unit (`scale` from SI), σ to one significant digit (two below 2) and
/// the value to the same decimal place, as uncertainty is quoted; `_digits` is the fallback
/// precision without a σ.
fn pm(v: f64, s: Option<f64>, scale: f64, _digits: usize) -> String {
    match s {
        Some(s) if s * scale > 0.0 && (s * scale).is_finite() => {
            let u = s * scale;
            let mut decimals = (-u.log10().floor()) as i32;
            if u / 10f64.powi(-decimals) < 2.0 {
                decimals += 1;
            }
            let d = decimals.clamp(0, 6) as usize;
            format!("{:.*} ± {:.*}", d, v * scale, d, u)
        }
        _ => format!("{:.3}", v * scale),
    }
}

fn get<'a>(
    params: &'a [(String, f64, Option<f64>, String)],
    name: &str,
) -> Option<&'a (String, f64, Option<f64>, String)> {
    params.iter().find(|p| p.0 == name)
}

/// The sentence a metrologist would write.
fn statement(
    f: &FoundTerm,
    params: &[(String, f64, Option<f64>, String)],
    c_wp: &[Vector3<f64>],
    main: usize,
) -> String {
    let axis = text_option(&f.config, "axis").unwrap_or_else(|| axis_name(main).into());
    let peak = c_wp.iter().map(|c| c[main].abs()).fold(0.0, f64::max);
    let list = || {
        params
            .iter()
            .map(|(n, v, s, u)| {
                let (scale, shown) = display(u, 1.0);
                format!(
                    "{n} = {}{}",
                    pm(*v, *s, scale, 2),
                    if shown.is_empty() {
                        String::new()
                    } else {
                        format!(" {shown}")
                    }
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    match f.id {
        TermId::ThermalScale => {
            let (_, a, s, _) = get(params, "alpha").cloned().unwrap_or_default();
            let sensors = f.variant.trim_start_matches("sensors ").trim_start_matches("sensor ");
            let mat = material(a, s.unwrap_or(0.0)).map(|m| format!(", consistent with {m}")).unwrap_or_default();
            format!("the {} scale expands with the {} temperature: α = {} µm/m/K{mat}", upper(&axis), sensors, pm(a, s, 1e6, 1))
        }
        TermId::Backlash => {
            let (_, b, s, _) = get(params, "reversal").cloned().unwrap_or_default();
            format!("{} µm reversal error on {}", pm(b, s, 1e6, 1), upper(&axis))
        }
        TermId::TrackerWarmup => {
            let (_, b, sb, _) = get(params, "amplitude").cloned().unwrap_or_default();
            let (_, tau, st, _) = get(params, "time_constant").cloned().unwrap_or_default();
            format!("tracker ranges drift {} µm with τ = {} min after power-on", pm(b, sb, 1e6, 1), pm(tau, st, 1.0 / 60.0, 0))
        }
        TermId::ThermalGrowth => {
            // the term's direction is +axis with a signed coefficient; said the way it moves
            // the tool as the structure warms: a positive rate along ±axis
            let (_, g, s, _) = get(params, "coefficient").cloned().unwrap_or_default();
            let sensor = text_option(&f.config, "sensor").unwrap_or_default();
            let axis = f.variant.split(',').next().unwrap_or("").trim().trim_start_matches("along ").to_string();
            let dir = if g < 0.0 { format!("along −{axis}") } else { format!("along +{axis}") };
            let lag = get(params, "time_constant").map(|(_, t, st, _)| format!(", lagging it by τ = {} min", pm(*t, *st, 1.0 / 60.0, 0))).unwrap_or_default();
            format!("the tool moves {dir} as the structure warms with the {sensor} temperature: {} µm/K{lag}", pm(g.abs(), s, 1e6, 2))
        }
        TermId::Positioning => format!("{} positions are off by up to {} µm over the travel ({}; {})", upper(&axis), um(peak), f.variant, list()),
        TermId::Straightness => format!("the {} motion is not straight along {}: up to {} µm over the travel ({})", upper(&axis), text_option(&f.config, "direction").map(|d| upper(&d)).unwrap_or_default(), um(peak), f.variant),
        TermId::Angular => format!("the {} carriage turns about {} as it moves: up to {} µm at the tool through its Abbe lever ({}; {})", upper(&axis), text_option(&f.config, "about").map(|d| upper(&d)).unwrap_or_default(), um(peak), f.variant, list()),
        TermId::Squareness => {
            let (_, s, sig, _) = get(params, "s").cloned().unwrap_or_default();
            let pair = text_option(&f.config, "pair").unwrap_or_default();
            format!("{} and {} are out of square by {} µrad ({} µm per metre)", upper(pair.get(0..1).unwrap_or("")), upper(pair.get(1..2).unwrap_or("")), pm(s, sig, 1e6, 1), pm(s, sig, 1e6, 1))
        }
        TermId::PitchCyclic => {
            let a = get(params, "a1").map(|p| p.1).unwrap_or(0.0);
            let b = get(params, "b1").map(|p| p.1).unwrap_or(0.0);
            let sa = get(params, "a1").and_then(|p| p.2).unwrap_or(0.0);
            let sb = get(params, "b1").and_then(|p| p.2).unwrap_or(0.0);
            let amp = (a * a + b * b).sqrt();
            let s_amp = if amp > 0.0 { ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp } else { sa.max(sb) };
            format!("the {} ball screw has a cyclic error of {} µm amplitude repeating every {} (its lead)", upper(&axis), pm(amp, Some(s_amp), 1e6, 1), f.variant.trim_start_matches("lead "))
        }
        TermId::Refraction => {
            let (_, t, s, _) = get(params, "path_temperature_offset").cloned().unwrap_or_default();
            format!("the air on the beam is {} K {} than the weather station reads: ranges read {} by about {:.2} µm/m", pm(t.abs(), s, 1.0, 2), if t > 0.0 { "warmer" } else { "cooler" }, if t > 0.0 { "short" } else { "long" }, t.abs() * 0.93)
        }
        TermId::TimeOffset => {
            let (_, dt, s, _) = get(params, "latency").cloned().unwrap_or_default();
            format!("the measurements {} the machine positions by {} ms: the error grows with feed rate ({} µm at 100 mm/s)", if dt >= 0.0 { "lag" } else { "lead" }, pm(dt.abs(), s, 1e3, 1), um(dt.abs() * 0.1))
        }
        TermId::ToolOffset => format!("the tool offset is off by ({})", list()),
        TermId::InstrumentDrift => drift_statement(params, c_wp, &f.variant),
        TermId::JointCompliance | TermId::JointBacklash => {
            let (what, unit, scale) = if f.id == TermId::JointCompliance { ("yield to the gravity torque", "µrad/(N·m)", 1e6) } else { ("have play taken up to the side gravity pushes", "µrad", 1e6) };
            let joints: Vec<String> = params.iter().filter(|(_, v, s, _)| s.is_some_and(|s| v.abs() > 2.0 * s)).map(|(n, v, s, _)| format!("{} {}", &n[2..], pm(*v, *s, scale, 1))).collect();
            format!("the robot's joints {what}: {} {unit}; up to {} µm at the tool", if joints.is_empty() { list() } else { joints.join(", ") }, um(c_wp.iter().map(|c| c.norm()).fold(0.0, f64::max)))
        }
        TermId::ColumnBending => format!("the lifting column leans under the moment of what it carries: {}; up to {} µm at the tool", list(), um(c_wp.iter().map(|c| c.norm()).fold(0.0, f64::max))),
        TermId::LinkThermalExpansion => {
            let (_, a, s, _) = get(params, "alpha").cloned().unwrap_or_default();
            let sensor = text_option(&f.config, "sensor").unwrap_or_default();
            format!("the robot's links expand with the {sensor} temperature: α = {} µm/m/K, up to {} µm at the tool", pm(a, s, 1e6, 1), um(c_wp.iter().map(|c| c.norm()).fold(0.0, f64::max)))
        }
        TermId::Compliance => format!("the structure deflects under load as {} extends: up to {} µm ({})", upper(&axis), um(peak), list()),
        TermId::RotaryAxisLocation => {
            let significant: Vec<String> = params.iter().filter(|(_, v, s, _)| s.is_some_and(|s| v.abs() > 2.0 * s)).map(|(n, v, s, u)| format!("{n} = {}{}", pm(*v, *s, 1e6, 1), if u == "m" { " µm" } else { " µrad" })).collect();
            format!("the rotary axes are not where the model puts them: {} (up to {} µm at the tool)", if significant.is_empty() { list() } else { significant.join(", ") }, um(peak))
        }
        TermId::ProbePretravel => {
            let (_, p0, s0, _) = get(params, "mean").cloned().unwrap_or_default();
            let a = get(params, "lobe_cos").map(|p| p.1).unwrap_or(0.0);
            let b = get(params, "lobe_sin").map(|p| p.1).unwrap_or(0.0);
            let (sa, sb) = (get(params, "lobe_cos").and_then(|p| p.2).unwrap_or(0.0), get(params, "lobe_sin").and_then(|p| p.2).unwrap_or(0.0));
            let amp = (a * a + b * b).sqrt();
            let s_amp = if amp > 0.0 { ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp } else { sa.max(sb) };
            let lobes = f.variant.trim_end_matches(" lobes");
            let vertical = get(params, "vertical").map(|(_, v, s, _)| format!(", {} µm probing down", pm(*v, *s, 1e6, 1))).unwrap_or_default();
            format!("the touch probe triggers {} µm late on average, varying by {} µm around its {lobes}-lobed seat{vertical}", pm(p0, s0, 1e6, 1), pm(amp, Some(s_amp), 1e6, 1))
        }
        _ => format!("{} ({}): {}; up to {} µm", f.label, f.id.summary(), list(), um(peak)),
    }
}

/// The instrument's drift in words: how far its origin moved from the recording's start to its
/// end (a Legendre series changes by 2·c over the span for odd orders, 0 for even), and the
/// largest effect on the points.
fn drift_statement(
    params: &[(String, f64, Option<f64>, String)],
    c_wp: &[Vector3<f64>],
    variant: &str,
) -> String {
    let total = |axis: &str| -> (f64, f64) {
        let (mut v, mut s2) = (0.0, 0.0);
        for (n, x, s, _) in params {
            if let Some(order) = n.strip_prefix(axis).and_then(|o| o.parse::<usize>().ok()) {
                if order % 2 == 1 {
                    v += 2.0 * x;
                    s2 += (2.0 * s.unwrap_or(0.0)).powi(2);
                }
            }
        }
        (v, s2.sqrt())
    };
    let moves: Vec<String> = ["dx", "dy", "dz"]
        .iter()
        .map(|a| {
            let (v, s) = total(a);
            format!(
                "{} {} µm",
                &a[1..],
                pm(v, Some(s).filter(|s| *s > 0.0), 1e6, 1)
            )
        })
        .collect();
    let turns: Vec<String> = ["rx", "ry", "rz"]
        .iter()
        .filter(|a| params.iter().any(|p| p.0.starts_with(*a)))
        .map(|a| {
            let (v, s) = total(a);
            format!(
                "{} {} µrad",
                &a[1..],
                pm(v, Some(s).filter(|s| *s > 0.0), 1e6, 1)
            )
        })
        .collect();
    let peak = c_wp.iter().map(|c| c.norm()).fold(0.0, f64::max);
    format!(
        "the instrument moved during the recording ({variant}): its origin by {} from start to end{}; up to {} µm on the measured points",
        moves.join(", "),
        if turns.is_empty() { String::new() } else { format!(", turning by {}", turns.join(", ")) },
        um(peak)
    )
}

/// Structures no catalog term explains: the empirical corrections chosen, and localisation
/// findings left in the final residuals.
/// `empirical`: each correction's basis, coefficients, their σ, and its net effect on each record
/// along its axis (what the model's own parameters take of it projected out: the size a user
/// sees on the recorded points, never a coefficient).
pub fn unexplained(
    empirical: &[FittedEmpirical],
    view: &crate::residual_view::ResidualView,
    located_after: &[Located],
    records: &[MeasurementRecord],
) -> Vec<Unexplained> {
    let n = view.len();
    let t0 = view.time.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut out = Vec::new();
    for (basis, coefficients, sigmas, net) in empirical {
        let values: Vec<f64> = net.clone();
        let peak = values.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let rms = (values.iter().map(|v| v * v).sum::<f64>() / (3 * n).max(1) as f64).sqrt();
        let axis = axis_name(basis.axis);
        let big: Vec<usize> = (0..n).filter(|&i| values[i].abs() >= 0.5 * peak).collect();
        let channels: BTreeSet<String> = big.iter().map(|&i| records[i].channel.clone()).collect();
        let (description, statement) = match &basis.shape {
            EmpiricalShape::TimeSpline { knots, .. } => {
                let (a, b) = big.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| (a.min(view.time[i]), b.max(view.time[i])));
                // sign changes of the correction over time: a drift that cycles
                let mut order: Vec<usize> = (0..n).collect();
                order.sort_by(|&p, &q| view.time[p].total_cmp(&view.time[q]));
                let swings = order.windows(2).filter(|w| values[w[0]].signum() != values[w[1]].signum() && values[w[1]].abs() > 0.2 * peak).count();
                (
                    format!("the {axis} residuals vary in time: up to {} µm, largest between t = {:.2} h and {:.2} h into the recording, changing sign {swings} times", um(peak), (a - t0) / 3600.0, (b - t0) / 3600.0),
                    format!("the {axis} residuals drift {} in time (up to {} µm) and no catalog term explains it (nothing the recording's temperatures, air, power-on time or motion predict); an empirical time correction ({knots} knots, labelled empirical, not physics) takes it out", if swings >= 2 { "back and forth" } else { "" }, um(peak)).replace("drift  in", "drift in"),
                )
            }
            EmpiricalShape::WorkspaceBump { centre, width } => (
                format!("a local bump along {axis} of {} µm around x {:.0} mm, y {:.0} mm, z {:.0} mm, about {:.0} mm wide", um(peak), centre[0] * 1e3, centre[1] * 1e3, centre[2] * 1e3, width * 2e3),
                format!("a local {axis} error of {} µm around ({:.0}, {:.0}, {:.0}) mm, {:.0} mm wide, that no catalog term explains; an empirical bump correction (labelled empirical, not physics) takes it out", um(peak), centre[0] * 1e3, centre[1] * 1e3, centre[2] * 1e3, width * 2e3),
            ),
        };
        let correction = EmpiricalCorrection {
            label: basis.label(),
            basis: basis.clone(),
            coefficients_m: coefficients.clone(),
            coefficient_sigmas_m: sigmas.clone(),
            effect_rms_m: rms,
            empirical: true,
        };
        out.push(Unexplained {
            location: Where {
                channels: channels.into_iter().collect(),
                axis: axis.into(),
                description,
                located: Vec::new(),
            },
            correction: Some(correction),
            statement,
        });
    }
    for f in located_after.iter().take(5) {
        out.push(Unexplained {
            location: Where { channels: vec![f.channel.clone()], axis: axis_name(f.axis).into(), description: f.describe(), located: vec![f.describe()] },
            correction: None,
            statement: format!("structure left after the found terms that no catalog term explains and no empirical correction passed the held-out test for: {}", f.describe()),
        });
    }
    out
}

/// What to measure next, and what these records could not tell apart.
pub fn advice(
    selection: &FamilySelection,
    families: &[Family],
    records: &[MeasurementRecord],
    machine: &metrocell_model::MachineGeometry,
) -> Vec<String> {
    let mut out = Vec::new();
    // the machine's points (a reference nest has no axis position)
    let records: Vec<&MeasurementRecord> = records
        .iter()
        .filter(|r| !metrocell_estimation::is_reference(r))
        .collect();
    for k in 0..3 {
        let values: Vec<f64> = records
            .iter()
            .filter_map(|r| r.signals.axis_position[k])
            .collect();
        if values.len() != records.len() || values.is_empty() {
            continue;
        }
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let travel = machine.travel[k][1] - machine.travel[k][0];
        let distinct: BTreeSet<i64> = values.iter().map(|v| (v * 1e6).round() as i64).collect();
        let name = upper(axis_name(k));
        if travel.is_finite() && hi - lo < 0.25 * travel {
            out.push(format!("{name} moves over only {:.0} mm of its {:.0} mm travel: errors that grow along {name} (positioning, scale, straightness) cannot be told apart from a constant; measure points spanning the {name} travel", (hi - lo) * 1e3, travel * 1e3));
        } else if distinct.len() < 3 {
            out.push(format!("only {} distinct {name} positions: needs at least 3 (better 10) points spanning the {name} travel to tell a curved positioning error from a scale error, and both from a reversal error", distinct.len()));
        }
        let approaches: BTreeSet<i64> = records
            .iter()
            .filter_map(|r| r.signals.approach_direction[k])
            .map(|v| v as i64)
            .collect();
        if distinct.len() >= 2 && approaches.len() < 2 {
            out.push(format!("every {name} point was approached from the same side: a reversal (backlash) error on {name} cannot be told from a positioning offset; measure each point from both sides (a bidirectional ISO 230-2 run) — at least 5 points each way spanning the {name} travel"));
        }
    }
    if let Some(step) = selection.steps.first() {
        for s in &step.scores {
            if !s.separable
                && s.wald_p_adjusted >= 1.0
                && families.iter().any(|f| f.label == s.label && f.physical)
            {
                // not separable from the declared terms after pruning: only said for terms whose
                // held-out gain would have been large
                let gain = s.heldout_gain;
                if gain > 0.05 {
                    out.push(format!("{} would explain {:.0} % of the held-out error but cannot be separated from terms already in the model with these records", s.label, 100.0 * gain));
                }
            }
        }
    }
    out
}

/// The answer in one paragraph.
pub fn summary(
    findings: &[Finding],
    unexplained: &[Unexplained],
    before: &FitFigures,
    after: &FitFigures,
    noise: f64,
    explained: bool,
) -> String {
    let mut s = String::new();
    if findings.is_empty() {
        s.push_str("No catalog term is missing from the model");
        s.push_str(if unexplained.is_empty() {
            "."
        } else {
            " that these records can show."
        });
    } else {
        s.push_str(&format!(
            "The model lacked {}: ",
            if findings.len() == 1 {
                "one effect".to_string()
            } else {
                format!("{} effects", findings.len())
            }
        ));
        s.push_str(
            &findings
                .iter()
                .map(|f| f.statement.clone())
                .collect::<Vec<_>>()
                .join("; "),
        );
        s.push('.');
    }
    for u in unexplained {
        s.push(' ');
        s.push_str(&u.statement);
        s.push('.');
    }
    s.push_str(&format!(
        " Held-out RMS {} µm before, {} µm after (noise floor {} µm, χ²/dof {:.2} → {:.2}); {}",
        um(before.heldout_rms_m),
        um(after.heldout_rms_m),
        um(noise),
        before.chi2_per_dof,
        after.chi2_per_dof,
        if explained {
            "what remains is consistent with noise."
        } else {
            "what remains is not all explained by catalog physics."
        }
    ));
    s
}

/// The parameters of `label` outside their usual range, each with what that most likely means.
fn unusual_values(inputs: &Inputs, label: &str) -> Vec<String> {
    let specs: Vec<_> = inputs
        .model
        .machine_terms
        .param_specs()
        .into_iter()
        .chain(inputs.model.instrument_terms.param_specs())
        .collect();
    let mut out = Vec::new();
    for (k, name) in inputs.names.iter().enumerate() {
        let Some(param) = name.strip_prefix(&format!("{label}.")) else {
            continue;
        };
        if !inputs.free[k] {
            continue;
        }
        let spec = &specs[k];
        let v = inputs.x[k];
        if let Some((_, side)) = inputs.at_bound.iter().find(|(n, _)| n == name) {
            let (shown, unit) = display(spec.unit, v);
            out.push(format!("{param} = {shown:.3} {unit} is on the {side} bound of its possible range: the data want a value beyond it, which the physics does not allow, and no interior σ can be given"));
            continue;
        }
        if spec.usual.contains(v) {
            continue;
        }
        let (shown, unit) = display(spec.unit, v);
        let (lo, _) = display(spec.unit, spec.usual.lo);
        let (hi, _) = display(spec.unit, spec.usual.hi);
        let meaning = if spec.unusual_means.is_empty() {
            String::new()
        } else {
            format!(": {}", spec.unusual_means)
        };
        out.push(format!(
            "{param} = {} {unit} is outside the usual {} … {} {unit}{meaning}",
            significant(shown),
            significant(lo),
            significant(hi)
        ));
    }
    out
}

/// Three significant digits, however small or large (no "0.000" for a compliance in SI).
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.decimals$}")
}

/// A value in the unit metrologists read it in.
fn display(unit: &str, v: f64) -> (f64, &'static str) {
    match unit {
        "m" => (v * 1e6, "µm"),
        "rad" => (v * 1e6, "µrad"),
        "1/K" => (v * 1e6, "µm/m/K"),
        "m/K" => (v * 1e6, "µm/K"),
        "s" => (v / 60.0, "min"),
        "K" => (v, "K"),
        "Pa" => (v / 100.0, "hPa"),
        // the gravity terms: compliances of joints and columns
        "rad/(N m)" => (v * 1e6, "µrad/(N·m)"),
        "rad m^2/(N m)" => (v * 1e6, "µrad·m²/(N·m)"),
        "1/(N m^2)" => (v * 1e6, "1/(MN·m²)"),
        _ => (v, ""),
    }
}

/// What measurement would tell two confounded terms apart.
pub fn separated_by(a: &str, b: &str) -> String {
    let pair = |x: &str, y: &str| (a == x && b == y) || (a == y && b == x);
    let either = |x: &str| a == x || b == x;
    if either("instrument_drift") {
        "re-measure a fixed reference nest (on the floor, or a point the machine does not move) every 30 min through the shift: the instrument's drift moves the nest, the machine's physics does not".into()
    } else if pair("tracker_warmup", "refraction") || either("refraction") {
        "measure the same points from a second instrument position, or log the air along the beam: refraction scales every range, a warm-up adds the same length to each".into()
    } else if either("tracker_warmup") {
        "let the tracker warm up (or record its power-on time and measure a reference nest through the first hours): its drift follows the time since power-on, the machine's physics does not".into()
    } else if either("thermal_growth") || either("thermal_scale") {
        "repeat the measurement at another temperature, or with the temperatures changing differently in time: a thermal term follows its sensor".into()
    } else if either("backlash")
        || either("pitch_cyclic")
        || either("positioning")
        || either("straightness")
        || either("squareness")
        || either("angular")
    {
        "measure more positions along the axis, from both directions (an ISO 230-2 bidirectional run over irregular positions)".into()
    } else {
        "a measurement where their effects differ (other positions, times or conditions)".into()
    }
}

/// The alternatives each chosen family was not told apart from, per label.
pub fn alternatives_of(
    selection: &FamilySelection,
    families: &[Family],
) -> BTreeMap<String, Vec<Alternative>> {
    let mut out: BTreeMap<String, Vec<Alternative>> = BTreeMap::new();
    for step in &selection.steps {
        let Some(c) = step.chosen else { continue };
        let chosen = &families[c];
        for a in &step.alternatives {
            let f = &families[a.family];
            out.entry(chosen.label.clone())
                .or_default()
                .push(Alternative {
                    term: f.term.clone(),
                    label: f.label.clone(),
                    variant: f
                        .variants
                        .get(a.variant)
                        .map(|v| v.name.clone())
                        .unwrap_or_default(),
                    delta_bic: a.delta_bic,
                    correlation: a.correlation,
                    separated_by: separated_by(&chosen.term, &f.term),
                });
        }
    }
    out
}
