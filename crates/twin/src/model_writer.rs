//! Writing a fitted model back as a cell file: the user's own file, with the fitted values in
//! place, their standard uncertainties in an `uncertainty:` section, terms found later (by
//! `diagnose`) appended to `terms:`, and a `fit:` section saying what the fit saw.
//!
//! What is kept: every byte the update does not change — comments (also inside `params`),
//! blank lines, key order, flow or block style, quoting, and the unit each value was written
//! in (`c1: 12 um` becomes `c1: 11.87 um`; a bare number stays a bare SI number). What changes:
//! * each fitted value of a `terms[i]` parameter, in place (a parameter the file left to its
//!   default is added to `params`); the tracker's `pose` (`translation`, `euler_xyz`), `warmup`
//!   parameters, the probe's `pretravel` parameters, and for `refraction` the station's `temperature_bias` / `pressure_bias`
//!   (path offset = beam offset − station bias, so the file reads back as the same term);
//! * `uncertainty:` — standard uncertainties (k = 1) by term label and parameter, in the unit
//!   of the value (merged with an existing section: parameters not refitted keep theirs);
//! * `fit:` — replaced as a whole.
//!
//! Values are rounded to 1/100 of their uncertainty or finer (GUM: the uncertainty decides the
//! digits), uncertainties to two significant digits. Parameters without an uncertainty (fixed,
//! or not identifiable) are not rewritten. The output reads back with [`CellModel`], and with
//! [`crate::Cell`] when the input was a full cell.

use std::collections::BTreeMap;

use metrocell_physics::config::ConfigValue;
use metrocell_physics::units::{parse_quantity, split_quantity};
use metrocell_physics::{configure, TermConfig, TermId};

use crate::cell_model::CellModel;
use crate::error::CellError;
use crate::yaml_edit::{self, add_to_mapping, append_to_block_sequence, key_text, Edits, Node};

/// One fitted parameter: `label.param`, value and standard uncertainty in its canonical unit.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedParameter {
    pub name: String,
    pub value: f64,
    /// None: not identifiable (the value is not written).
    pub sigma: Option<f64>,
}

/// What to write into a model file.
#[derive(Debug, Clone, Default)]
pub struct ModelUpdate {
    /// Fitted values; parameters not listed keep what the file says.
    pub parameters: Vec<FittedParameter>,
    /// Terms to append to `terms:` (e.g. found by `diagnose`); their `params` are overwritten by
    /// the fitted values of `parameters` with their label.
    pub added_terms: Vec<TermConfig>,
    /// The `fit:` section (replaces an existing one).
    pub fit: Option<serde_yaml::Value>,
    /// Sentences written as comments above the appended sections: what the writer of the file
    /// (e.g. `diagnose`) found but could not put in a model file, and why.
    pub notes: Vec<String>,
    /// The directory the written file goes to: a relative path the file gives (its URDF) is
    /// rewritten to hold from there (made absolute) when that is not the file's own directory.
    pub output_dir: Option<std::path::PathBuf>,
}

pub(crate) fn bad(model: &CellModel, reason: String) -> CellError {
    CellError::InFile {
        file: model.file.clone(),
        error: Box::new(CellError::Invalid {
            path: "(writing the fitted model)".into(),
            reason,
        }),
    }
}

/// A relative path of the file (`node`) as it must read from `dir`: absolute, unless `dir` is
/// the file's own directory (then as written).
fn relocated_path(
    model: &CellModel,
    dir: &std::path::Path,
    node: &yaml_edit::Node,
    edits: &mut Edits,
) {
    let Some(path) = node.scalar() else { return };
    let path = path.trim_matches(|c| c == '"' || c == '\'');
    if std::path::Path::new(path).is_absolute() {
        return;
    }
    let canon = |p: &std::path::Path| std::fs::canonicalize(p).ok();
    let here = if dir.as_os_str().is_empty() {
        std::path::Path::new(".")
    } else {
        dir
    };
    if canon(here).is_some() && canon(here) == canon(&model.base_dir) {
        return;
    }
    if let Some(absolute) = canon(&model.base_dir.join(path)) {
        edits.replace(node, format!("{:?}", absolute.display().to_string()));
    }
}

/// The model file's text with `update` applied (see the module docs).
pub fn write_model(model: &CellModel, update: &ModelUpdate) -> Result<String, CellError> {
    let text = &model.text;
    let root = yaml_edit::parse(text).map_err(|e| bad(model, e.0))?;
    let fitted: BTreeMap<&str, &FittedParameter> = update
        .parameters
        .iter()
        .map(|p| (p.name.as_str(), p))
        .collect();
    let mut edits = Edits::default();
    // value text and uncertainty text of each written parameter, by label then param
    let mut written: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();

    machine_term_edits(model, &root, &fitted, &mut edits, &mut written)?;
    if model.declares_tracker {
        tracker_edits(model, &root, &fitted, &mut edits, &mut written)?;
    }
    if let (Some(dir), Some(node)) = (&update.output_dir, root.at("machine.serial_arm.urdf.path")) {
        relocated_path(model, dir, node, &mut edits);
    }
    probe_edits(model, &root, &fitted, &mut edits, &mut written)?;
    let mut notes = update.notes.clone();
    // a term goes under `terms:` only if the loader takes it there; the others (an instrument's)
    // go where a model file keeps them, or are left out and said
    let (machine, instrument): (Vec<TermConfig>, Vec<TermConfig>) =
        update.added_terms.iter().cloned().partition(|c| {
            metrocell_model_file::terms_section::home_of(&c.id).is_none()
                && metrocell_model_file::terms_section::terms(
                    std::slice::from_ref(c),
                    None,
                    None,
                    &model.machine,
                )
                .is_ok()
        });
    if !machine.is_empty() {
        added_terms(model, &root, &fitted, &machine, &mut edits, &mut written)?;
    }
    if !instrument.is_empty() {
        notes.extend(crate::model_writer_instruments::added_instrument_terms(
            model,
            &root,
            &fitted,
            &instrument,
            &mut edits,
            &mut written,
        )?);
    }

    // uncertainty: merged with what the file had, rewritten as a whole at the end
    let mut sections = String::new();
    if !notes.is_empty() {
        sections.push_str(&note_lines(&notes));
    }
    let merged = merged_uncertainty(text, &root, written);
    if !merged.is_empty() {
        sections.push_str(&uncertainty_section(&merged));
    }
    if let Some(fit) = &update.fit {
        sections.push_str(&fit_section(model, fit)?);
    }
    // drop the old sections (key line through value), append the new ones at the end
    for key in ["uncertainty", "fit"] {
        let replaced =
            (key == "uncertainty" && !merged.is_empty()) || (key == "fit" && update.fit.is_some());
        if let (true, Some(k), Some(v)) = (replaced, root.key(key), root.get(key)) {
            drop_lines(text, k, v, &mut edits);
        }
    }
    let mut out = edits.apply(text).map_err(|e| bad(model, e.0))?;
    if !sections.is_empty() {
        if !out.ends_with('\n') {
            out.push('\n');
        }
        out.push_str(&sections);
    }
    Ok(out)
}

/// The fitted values of the declared machine terms' parameters written in place (in the unit
/// the file gave, or added to the term's `params`), each one's uncertainty text kept in
/// `written`.
fn machine_term_edits(
    model: &CellModel,
    root: &Node,
    fitted: &BTreeMap<&str, &FittedParameter>,
    edits: &mut Edits,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), CellError> {
    let text = &model.text;
    for (i, t) in model.machine_terms.terms.iter().enumerate() {
        let label = t.term.label();
        let Some(node) = root.at(&format!("terms[{i}]")) else {
            return Err(bad(model, format!("terms[{i}] not found in the text")));
        };
        for spec in t.term.params() {
            let Some(p) = fitted.get(format!("{label}.{}", spec.name).as_str()) else {
                continue;
            };
            let Some(sigma) = p.sigma else { continue };
            let unit = node
                .at(&format!("params.{}", spec.name))
                .map(|n| unit_in(text, n))
                .unwrap_or_default();
            let (value, u) =
                value_and_sigma(p.value, sigma, spec.unit, &unit).map_err(|e| bad(model, e))?;
            match node.at(&format!("params.{}", spec.name)) {
                Some(v) => edits.replace(v, value),
                None => match node.get("params") {
                    Some(params) => add_to_mapping(edits, text, params, &spec.name, &value),
                    None => add_to_mapping(
                        edits,
                        text,
                        node,
                        "params",
                        &format!("{{{}: {value}}}", spec.name),
                    ),
                },
            }
            written
                .entry(label.clone())
                .or_default()
                .insert(spec.name.clone(), u);
        }
    }
    Ok(())
}

/// The uncertainties the file had, with the ones written now over them (label → param → text).
fn merged_uncertainty(
    text: &str,
    root: &Node,
    written: BTreeMap<String, BTreeMap<String, String>>,
) -> BTreeMap<String, BTreeMap<String, String>> {
    let mut merged: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    if let Some(old) = root.get("uncertainty") {
        if let yaml_edit::Content::Mapping(entries) = &old.content {
            for (label, _, params) in entries {
                if let yaml_edit::Content::Mapping(ps) = &params.content {
                    for (name, _, v) in ps {
                        let value = v
                            .scalar()
                            .map(|s| flow(&ConfigValue::Text(s.to_string())))
                            .unwrap_or_else(|| text[v.start..v.end].to_string());
                        merged
                            .entry(label.clone())
                            .or_default()
                            .insert(name.clone(), value);
                    }
                }
            }
        }
    }
    for (label, ps) in written {
        merged.entry(label).or_default().extend(ps);
    }
    merged
}

/// The `uncertainty:` section of `merged`.
fn uncertainty_section(merged: &BTreeMap<String, BTreeMap<String, String>>) -> String {
    let mut section = String::from("uncertainty:                   # standard uncertainties (k = 1) of the fitted values, written by metrocell calibrate\n");
    for (label, ps) in merged {
        let items: Vec<String> = ps
            .iter()
            .map(|(k, v)| format!("{}: {v}", key_text(k)))
            .collect();
        section.push_str(&format!(
            "  {}: {{{}}}\n",
            key_text(label),
            items.join(", ")
        ));
    }
    section
}

/// The `fit:` section: what the fit saw.
fn fit_section(model: &CellModel, fit: &serde_yaml::Value) -> Result<String, CellError> {
    let body = serde_yaml::to_string(fit).map_err(|e| bad(model, format!("fit section: {e}")))?;
    let mut section = String::from(
        "fit:                           # what the fit saw, written by metrocell calibrate\n",
    );
    for line in body.lines() {
        section.push_str(&format!("  {line}\n"));
    }
    Ok(section)
}

/// Drop a top-level section's lines: from its key's line through the end of its value.
fn drop_lines(text: &str, k: &Node, v: &Node, edits: &mut Edits) {
    let line_start = text[..k.start].rfind('\n').map(|i| i + 1).unwrap_or(0);
    let line_end = text[v.end..]
        .find('\n')
        .map(|i| v.end + i + 1)
        .unwrap_or(text.len());
    edits.replace(
        &Node {
            start: line_start,
            end: line_end,
            ..k.clone()
        },
        String::new(),
    );
}

/// The unit a value node was written in (empty: a bare number in the canonical unit).
fn unit_in(text: &str, node: &Node) -> String {
    let raw = match node.scalar() {
        Some(s) => s,
        None => text[node.start..node.end].trim_matches(|c| c == '"' || c == '\''),
    };
    split_quantity(raw).1.to_string()
}

/// Notes as comment lines, each wrapped at about 100 characters.
fn note_lines(notes: &[String]) -> String {
    let mut out = String::new();
    for n in notes {
        let mut line = String::from("# -");
        for word in n.split_whitespace() {
            if line.len() + word.len() > 100 {
                out.push_str(&line);
                out.push('\n');
                line = String::from("#  ");
            }
            line.push(' ');
            line.push_str(word);
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

/// `value` (canonical unit) in `unit` ("" = canonical), and the uncertainty in the same unit.
pub(crate) fn value_and_sigma(
    value: f64,
    sigma: f64,
    canonical: &str,
    unit: &str,
) -> Result<(String, String), String> {
    let (v, s) = to_unit(value, canonical, unit)?;
    let scale = if unit.is_empty() {
        1.0
    } else {
        parse_quantity(&format!("1 {unit}"), canonical).map_err(|e| format!("{e:?}"))?
            - parse_quantity(&format!("0 {unit}"), canonical).map_err(|e| format!("{e:?}"))?
    };
    let su = sigma / scale;
    let _ = s;
    let value_text = number(v, Some(resolution(su / 100.0)));
    let sigma_text = if su > 0.0 {
        number(su, Some(resolution(su) / 10.0))
    } else {
        "0".into()
    };
    let with_unit = |n: String| {
        if unit.is_empty() {
            n
        } else {
            format!("{n} {unit}")
        }
    };
    Ok((with_unit(value_text), with_unit(sigma_text)))
}

/// `value` (canonical) converted to `unit`; also returns the unit's scale.
fn to_unit(value: f64, canonical: &str, unit: &str) -> Result<(f64, f64), String> {
    if unit.is_empty() {
        return Ok((value, 1.0));
    }
    let one = parse_quantity(&format!("1 {unit}"), canonical)
        .map_err(|e| format!("unit `{unit}`: {e:?}"))?;
    let zero = parse_quantity(&format!("0 {unit}"), canonical)
        .map_err(|e| format!("unit `{unit}`: {e:?}"))?;
    Ok(((value - zero) / (one - zero), one - zero))
}

/// The power of ten at or below `x` (x > 0).
fn resolution(x: f64) -> f64 {
    if x > 0.0 && x.is_finite() {
        10f64.powf(x.log10().floor())
    } else {
        1e-12
    }
}

/// `v` written to a multiple of `step` (a power of ten): plain decimals where short, otherwise
/// scientific with the same significant digits. None: the shortest text that reads back exactly.
pub fn number(v: f64, step: Option<f64>) -> String {
    let Some(step) = step else {
        return format!("{v}");
    };
    let decimals = (-step.log10().round()).max(0.0) as usize;
    let magnitude = if v == 0.0 {
        step.log10().round()
    } else {
        v.abs().log10().floor()
    };
    if (v.abs() >= 1e-3 || v == 0.0) && decimals <= 6 && magnitude < 9.0 {
        return format!("{:.*}", decimals, v);
    }
    let significant = (magnitude - step.log10().round() + 1.0).clamp(1.0, 17.0) as usize;
    let s = format!("{:.*e}", significant - 1, v);
    s.replace("e0", "").to_string()
}

fn tracker_edits(
    model: &CellModel,
    root: &Node,
    fitted: &BTreeMap<&str, &FittedParameter>,
    edits: &mut Edits,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), CellError> {
    let text = &model.text;
    let Some(tracker) = root.at("sensors.tracker") else {
        return Ok(());
    };
    let get = |n: &str| fitted.get(n).filter(|p| p.sigma.is_some()).copied();
    // pose: translation (m) and euler_xyz (rad), each written as a whole in the file's units
    if let Some(pose) = tracker.get("pose") {
        for (key, names, canonical, default_unit) in [
            ("translation", ["tx", "ty", "tz"], "m", "mm"),
            ("euler_xyz", ["alpha", "beta", "delta"], "rad", "deg"),
        ] {
            let ps: Vec<_> = names
                .iter()
                .map(|n| get(&format!("tracker_pose.{n}")))
                .collect();
            if ps.iter().all(|p| p.is_none()) {
                continue;
            }
            let node = pose.get(key);
            let unit = node
                .and_then(|n| n.item(0))
                .map(|n| unit_in(text, n))
                .unwrap_or_else(|| default_unit.into());
            let mut items = Vec::new();
            for (k, p) in ps.iter().enumerate() {
                let item = match p {
                    Some(p) => {
                        let (v, u) =
                            value_and_sigma(p.value, p.sigma.unwrap_or(0.0), canonical, &unit)
                                .map_err(|e| bad(model, e))?;
                        written
                            .entry("tracker_pose".into())
                            .or_default()
                            .insert(names[k].into(), u);
                        v
                    }
                    None => node
                        .and_then(|n| n.item(k))
                        .map(|n| text[n.start..n.end].to_string())
                        .unwrap_or_else(|| format!("0 {unit}")),
                };
                items.push(item);
            }
            match node {
                Some(n) => yaml_edit::replace_sequence(edits, n, &items)
                    .map_err(|e| bad(model, format!("sensors.tracker.pose.{key}: {e}")))?,
                None => add_to_mapping(edits, text, pose, key, &format!("[{}]", items.join(", "))),
            }
        }
    }
    // warm-up parameters in place
    if let Some(w) = tracker.get("warmup") {
        if let Some(t) = model
            .instrument_terms
            .terms
            .iter()
            .find(|t| t.term.id() == TermId::TrackerWarmup)
        {
            for spec in t.term.params() {
                let Some(p) = get(&format!("tracker_warmup.{}", spec.name)) else {
                    continue;
                };
                let node = w.get(&spec.name);
                let unit = node.map(|n| unit_in(text, n)).unwrap_or_default();
                let (v, u) = value_and_sigma(p.value, p.sigma.unwrap_or(0.0), spec.unit, &unit)
                    .map_err(|e| bad(model, e))?;
                match node {
                    Some(n) => edits.replace(n, v),
                    None => add_to_mapping(edits, text, w, &spec.name, &v),
                }
                written
                    .entry("tracker_warmup".into())
                    .or_default()
                    .insert(spec.name.clone(), u);
            }
        }
    }
    // refraction: path offset = beam offset − station bias (a refraction the file did not
    // declare is an added term: `model_writer_instruments` writes it)
    if !model
        .instrument_terms
        .terms
        .iter()
        .any(|t| t.term.id() == TermId::Refraction)
    {
        return Ok(());
    }
    let beam = model
        .raw
        .environment
        .as_ref()
        .and_then(|e| e.air.beam_temperature_offset.as_ref())
        .map(|q| q.to_si("environment.air.beam_temperature_offset", "K"))
        .transpose()?
        .unwrap_or(0.0);
    for (param, key, unit, offset) in [
        ("path_temperature_offset", "temperature_bias", "K", beam),
        ("path_pressure_offset", "pressure_bias", "Pa", 0.0),
    ] {
        let Some(p) = get(&format!("refraction.{param}")) else {
            continue;
        };
        let station_value = offset - p.value;
        let (v, u) = value_and_sigma(station_value, p.sigma.unwrap_or(0.0), unit, unit)
            .map_err(|e| bad(model, e))?;
        match tracker.get("station") {
            Some(st) => match st.get(key) {
                Some(n) => edits.replace(n, v),
                None => add_to_mapping(edits, text, st, key, &v),
            },
            None => add_to_mapping(edits, text, tracker, "station", &format!("{{{key}: {v}}}")),
        }
        written
            .entry("refraction".into())
            .or_default()
            .insert(param.into(), u);
    }
    Ok(())
}

/// The probe's pretravel parameters in place (`sensors.probe.pretravel.params`).
fn probe_edits(
    model: &CellModel,
    root: &Node,
    fitted: &BTreeMap<&str, &FittedParameter>,
    edits: &mut Edits,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), CellError> {
    let text = &model.text;
    let Some(pretravel) = root.at("sensors.probe.pretravel") else {
        return Ok(());
    };
    let Some(t) = model
        .instrument_terms
        .terms
        .iter()
        .find(|t| t.term.id() == TermId::ProbePretravel)
    else {
        return Ok(());
    };
    let label = t.term.label();
    for spec in t.term.params() {
        let Some(p) = fitted
            .get(format!("{label}.{}", spec.name).as_str())
            .filter(|p| p.sigma.is_some())
            .copied()
        else {
            continue;
        };
        let node = pretravel.get("params").and_then(|ps| ps.get(&spec.name));
        let unit = node.map(|n| unit_in(text, n)).unwrap_or_default();
        let (v, u) = value_and_sigma(p.value, p.sigma.unwrap_or(0.0), spec.unit, &unit)
            .map_err(|e| bad(model, e))?;
        match (node, pretravel.get("params")) {
            (Some(n), _) => edits.replace(n, v),
            (None, Some(ps)) => add_to_mapping(edits, text, ps, &spec.name, &v),
            (None, None) => add_to_mapping(
                edits,
                text,
                pretravel,
                "params",
                &format!("{{{}: {v}}}", spec.name),
            ),
        }
        written
            .entry(label.clone())
            .or_default()
            .insert(spec.name.clone(), u);
    }
    Ok(())
}

fn added_terms(
    model: &CellModel,
    root: &Node,
    fitted: &BTreeMap<&str, &FittedParameter>,
    terms: &[TermConfig],
    edits: &mut Edits,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
) -> Result<(), CellError> {
    let text = &model.text;
    let mut items = Vec::new();
    for (k, c) in terms.iter().enumerate() {
        let configured = configure(c).map_err(|e| CellError::InFile {
            file: model.file.clone(),
            error: Box::new(CellError::term(
                format!("added term {k} (id `{}`)", c.id),
                e,
            )),
        })?;
        let label = configured.term.label();
        let mut params = Vec::new();
        for (spec, configured_value) in configured.term.params().iter().zip(&configured.params) {
            let given_unit = match c.params.get(&spec.name) {
                Some(ConfigValue::Text(t)) => split_quantity(t).1.to_string(),
                _ => String::new(),
            };
            let unit = if given_unit.is_empty() {
                spec.unit.to_string()
            } else {
                given_unit
            };
            let unit = if unit == "1" { String::new() } else { unit };
            let value = match fitted.get(format!("{label}.{}", spec.name).as_str()) {
                Some(p) => match p.sigma {
                    Some(s) => {
                        let (v, u) = value_and_sigma(p.value, s, spec.unit, &unit)
                            .map_err(|e| bad(model, e))?;
                        written
                            .entry(label.clone())
                            .or_default()
                            .insert(spec.name.clone(), u);
                        v
                    }
                    None => with_unit(p.value, spec.unit, &unit).map_err(|e| bad(model, e))?,
                },
                None => {
                    with_unit(*configured_value, spec.unit, &unit).map_err(|e| bad(model, e))?
                }
            };
            params.push(format!("{}: {value}", key_text(&spec.name)));
        }
        let mut item = format!("id: {}", c.id);
        if !c.options.is_empty() {
            item += &format!("\noptions: {}", flow(&ConfigValue::Map(c.options.clone())));
        }
        item += &format!("\nparams: {{{}}}", params.join(", "));
        items.push(item);
    }
    match root.get("terms") {
        Some(seq) if !seq.is_flow() => {
            for item in &items {
                append_to_block_sequence(edits, text, seq, item);
            }
        }
        Some(seq) => {
            // a flow list (`terms: []`): rewrite it as flow items
            let mut all: Vec<String> = match &seq.content {
                yaml_edit::Content::Sequence(old) => old
                    .iter()
                    .map(|n| text[n.start..n.end].to_string())
                    .collect(),
                _ => vec![],
            };
            all.extend(
                items
                    .iter()
                    .map(|i| format!("{{{}}}", i.replace('\n', ", "))),
            );
            edits.replace(seq, format!("[{}]", all.join(", ")));
        }
        None => {
            let body: String = items
                .iter()
                .map(|i| format!("\n  - {}", i.replace('\n', "\n    ")))
                .collect();
            edits.insert(
                text.len(),
                format!(
                    "{}terms:{body}\n",
                    if text.ends_with('\n') { "" } else { "\n" }
                ),
            );
        }
    }
    Ok(())
}

pub(crate) fn with_unit(value: f64, canonical: &str, unit: &str) -> Result<String, String> {
    let (v, _) = to_unit(value, canonical, unit)?;
    Ok(if unit.is_empty() {
        number(v, None)
    } else {
        format!("{} {unit}", number(v, None))
    })
}

/// A config value as flow YAML.
pub(crate) fn flow(v: &ConfigValue) -> String {
    match v {
        ConfigValue::Bool(b) => b.to_string(),
        ConfigValue::Number(n) => number(*n, None),
        ConfigValue::Text(t) => {
            let plain = !t.is_empty()
                && !t.starts_with(|c: char| "[]{}#&*!|>'\"%@`,-?: ".contains(c))
                && !t.contains([',', '[', ']', '{', '}', '#', ':']);
            if plain {
                t.clone()
            } else {
                format!("\"{}\"", t.replace('\\', "\\\\").replace('"', "\\\""))
            }
        }
        ConfigValue::List(items) => format!(
            "[{}]",
            items.iter().map(flow).collect::<Vec<_>>().join(", ")
        ),
        ConfigValue::Map(m) => format!(
            "{{{}}}",
            m.iter()
                .map(|(k, v)| format!("{}: {}", key_text(k), flow(v)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn numbers_follow_their_resolution() {
        assert_eq!(number(11.8734, Some(0.01)), "11.87");
        assert_eq!(number(-2.0, Some(0.001)), "-2.000");
        assert_eq!(number(1.02134e-5, Some(1e-9)), "1.0213e-5");
        assert_eq!(number(0.5, None), "0.5");
        assert_eq!(number(4.1234e-7, Some(1e-8)), "4.1e-7");
        assert_eq!(number(0.0, Some(1e-3)), "0.000");
    }
}
