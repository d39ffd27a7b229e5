//! Instrument terms found later (by `diagnose`) written where a model file keeps them — the
//! loader refuses them under `terms:` ("is a sensor term"), so the writer puts each in its
//! sensor's section, as the twin and [`CellModel`] read it back:
//! * `tracker_warmup` → `sensors.tracker.warmup {offset, amplitude, time_constant}`;
//! * `refraction` → `sensors.tracker.station` biases (path offset = beam offset − station bias,
//!   `environment.air.beam_temperature_offset` or 0; pressure and humidity: −bias);
//! * `probe_pretravel` → `sensors.probe.pretravel {options, params}`.
//!
//! A model without `sensors.tracker` gets one without `pose` (the pose is unknown: registered
//! from each recording, as it was for the file the terms were found with). Any other term the
//! loader does not take under `terms:` is left out — `instrument_drift`, the instrument moving
//! during one recording, belongs to that recording as its pose does — and the returned notes say
//! so and why; they are written into the file as comments.

use std::collections::BTreeMap;

use metrocell_physics::{configure, ConfiguredTerm, TermConfig, TermId};

use crate::cell_model::CellModel;
use crate::error::CellError;
use crate::model_writer::{bad, value_and_sigma, with_unit, FittedParameter};
use crate::yaml_edit::{add_to_mapping, key_text, Content, Edits, Node};

/// Keys to put into one sensor section: (key, [(sub-key, value text)]), e.g.
/// `("warmup", [("amplitude", "20.2 um"), …])`.
type SectionKeys = Vec<(String, Vec<(String, String)>)>;

/// The unit a found value is written in: µm for lengths, minutes for times, else canonical.
fn display_unit(canonical: &str) -> &str {
    match canonical {
        "m" => "um",
        "s" => "min",
        "1" => "",
        other => other,
    }
}

/// Place `terms` (instrument terms, as `diagnose` adds them) in their sensor sections; the
/// notes for the file.
pub(crate) fn added_instrument_terms(
    model: &CellModel,
    root: &Node,
    fitted: &BTreeMap<&str, &FittedParameter>,
    terms: &[TermConfig],
    edits: &mut Edits,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
) -> Result<Vec<String>, CellError> {
    let mut notes = Vec::new();
    let mut tracker: SectionKeys = Vec::new();
    let mut probe: SectionKeys = Vec::new();
    for (k, c) in terms.iter().enumerate() {
        let configured = configure(c).map_err(|e| CellError::InFile {
            file: model.file.clone(),
            error: Box::new(CellError::term(
                format!("added term {k} (id `{}`)", c.id),
                e,
            )),
        })?;
        let label = configured.term.label();
        match configured.term.id() {
            TermId::TrackerWarmup => {
                let values = params_in_units(model, &configured, fitted, written, &|spec: &str| display_unit(spec).to_string())?;
                tracker.push(("warmup".into(), values));
                notes.push(format!("{label}, found by metrocell diagnose, is in sensors.tracker.warmup (a warm-up is the tracker's, not the machine's)."));
            }
            TermId::Refraction => {
                tracker.push(("station".into(), station_biases(model, &configured, &label, fitted, written)?));
                notes.push(format!(
                    "{label}, found by metrocell diagnose, is in sensors.tracker.station as the weather station's bias (path air − station reading = − bias); a model holds refraction fixed unless `estimation: {{refraction: {{free: [path_temperature_offset]}}}}` frees it."
                ));
            }
            TermId::ProbePretravel => {
                if root.at("sensors.probe").is_none() {
                    notes.push(format!("{label} was found but is left out of this file: it belongs in sensors.probe.pretravel, and the file has no sensors.probe to hold it."));
                    continue;
                }
                let params = params_in_units(model, &configured, fitted, written, &|spec: &str| display_unit(spec).to_string())?;
                let options: Vec<(String, String)> = c.options.iter().map(|(k, v)| (k.clone(), crate::model_writer::flow(v))).collect();
                let mut entry = Vec::new();
                if !options.is_empty() {
                    entry.push(("options".to_string(), flow_map(&options)));
                }
                entry.push(("params".to_string(), flow_map(&params)));
                probe.push(("pretravel".into(), entry));
                notes.push(format!("{label}, found by metrocell diagnose, is in sensors.probe.pretravel."));
            }
            TermId::InstrumentDrift => notes.push(format!(
                "{label}, found by metrocell diagnose (the instrument moved during the recording), is left out of this file: like the tracker's pose it belongs to one recording (its span is on that recording's clock), not to the machine; diagnose looks for it in each recording it judges (values in the report's diagnosis.json)."
            )),
            _ => notes.push(match metrocell_model_file::terms_section::home_of(&c.id) {
                Some(home) => format!("{label} was found but is left out of this file: a model keeps it in {home}, which metrocell does not write; add it there by hand (values in the report's diagnosis.json)."),
                None => {
                    let why = metrocell_model_file::terms_section::terms(std::slice::from_ref(c), None, None, &model.machine).err().map(|e| e.to_string()).unwrap_or_default();
                    format!("{label} was found but is left out of this file, which cannot hold it ({why}); values in the report's diagnosis.json.")
                }
            }),
        }
    }
    if !tracker.is_empty() {
        match root.at("sensors.tracker") {
            Some(t) => into_section(model, t, &tracker, edits)?,
            None => {
                new_sensor(model, root, "tracker", &tracker, edits)?;
                notes.push("sensors.tracker has no pose: the tracker's pose is unknown here and registered from each recording; `metrocell sim` needs sensors.tracker.pose and its noise model (rate, range_noise, angular_noise) to simulate it.".into());
            }
        }
    }
    if !probe.is_empty() {
        let p = root.at("sensors.probe").expect("checked above");
        into_section(model, p, &probe, edits)?;
    }
    Ok(notes)
}

/// Each parameter of a found term as (name, value text) in the unit `unit_of(canonical)`, with
/// its uncertainty recorded in `written` where the fit gave one.
fn params_in_units(
    model: &CellModel,
    term: &ConfiguredTerm,
    fitted: &BTreeMap<&str, &FittedParameter>,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
    unit_of: &dyn Fn(&str) -> String,
) -> Result<Vec<(String, String)>, CellError> {
    let label = term.term.label();
    let mut out = Vec::new();
    for (spec, configured) in term.term.params().iter().zip(&term.params) {
        let unit = unit_of(spec.unit);
        let value = match fitted.get(format!("{label}.{}", spec.name).as_str()) {
            Some(FittedParameter {
                value,
                sigma: Some(s),
                ..
            }) => {
                let (v, u) =
                    value_and_sigma(*value, *s, spec.unit, &unit).map_err(|e| bad(model, e))?;
                written
                    .entry(label.clone())
                    .or_default()
                    .insert(spec.name.clone(), u);
                v
            }
            Some(p) => with_unit(p.value, spec.unit, &unit).map_err(|e| bad(model, e))?,
            None => with_unit(*configured, spec.unit, &unit).map_err(|e| bad(model, e))?,
        };
        out.push((spec.name.clone(), value));
    }
    Ok(out)
}

/// A found `refraction` as the weather station's biases (the loader's inverse: path offset =
/// beam offset − station bias for temperature, −bias for pressure and humidity).
fn station_biases(
    model: &CellModel,
    term: &ConfiguredTerm,
    label: &str,
    fitted: &BTreeMap<&str, &FittedParameter>,
    written: &mut BTreeMap<String, BTreeMap<String, String>>,
) -> Result<Vec<(String, String)>, CellError> {
    let beam = model
        .raw
        .environment
        .as_ref()
        .and_then(|e| e.air.beam_temperature_offset.as_ref())
        .map(|q| q.to_si("environment.air.beam_temperature_offset", "K"))
        .transpose()?
        .unwrap_or(0.0);
    let mut out = Vec::new();
    for ((spec, configured), (key, offset)) in term
        .term
        .params()
        .iter()
        .zip(&term.params)
        .zip([("temperature_bias", beam), ("pressure_bias", 0.0)])
    {
        let value = match fitted.get(format!("{label}.{}", spec.name).as_str()) {
            Some(FittedParameter {
                value,
                sigma: Some(s),
                ..
            }) => {
                let (v, u) = value_and_sigma(offset - value, *s, spec.unit, spec.unit)
                    .map_err(|e| bad(model, e))?;
                written
                    .entry(label.to_string())
                    .or_default()
                    .insert(spec.name.clone(), u);
                v
            }
            Some(p) => {
                with_unit(offset - p.value, spec.unit, spec.unit).map_err(|e| bad(model, e))?
            }
            None => {
                with_unit(offset - configured, spec.unit, spec.unit).map_err(|e| bad(model, e))?
            }
        };
        out.push((key.to_string(), value));
    }
    if let Some(h) = term.options.get("path_humidity_offset") {
        let h = metrocell_physics::config::quantity(label, "path_humidity_offset", h, "1")
            .map_err(|e| CellError::term("refraction.options.path_humidity_offset", e))?;
        if h != 0.0 {
            out.push((
                "humidity_bias".into(),
                with_unit(-h, "1", "").map_err(|e| bad(model, e))?,
            ));
        }
    }
    Ok(out)
}

fn flow_map(entries: &[(String, String)]) -> String {
    format!(
        "{{{}}}",
        entries
            .iter()
            .map(|(k, v)| format!("{}: {v}", key_text(k)))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// Put `keys` into an existing sensor section: a sub-key already there is replaced where it
/// stands, a new one added; a key the section lacks is added as a flow mapping.
fn into_section(
    model: &CellModel,
    section: &Node,
    keys: &SectionKeys,
    edits: &mut Edits,
) -> Result<(), CellError> {
    let text = &model.text;
    if !matches!(section.content, Content::Mapping(_)) {
        return Err(bad(
            model,
            "a sensor section to add a found term to is not a mapping".into(),
        ));
    }
    for (key, entries) in keys {
        match section.get(key) {
            Some(existing) if matches!(existing.content, Content::Mapping(_)) => {
                for (sub, value) in entries {
                    match existing.get(sub) {
                        Some(n) => edits.replace(n, value.clone()),
                        None => add_to_mapping(edits, text, existing, sub, value),
                    }
                }
            }
            Some(existing) => edits.replace(existing, flow_map(entries)),
            None => add_to_mapping(edits, text, section, key, &flow_map(entries)),
        }
    }
    Ok(())
}

/// A new `sensors.<name>` section holding `keys`, in `sensors` (created when the file has none).
fn new_sensor(
    model: &CellModel,
    root: &Node,
    name: &str,
    keys: &SectionKeys,
    edits: &mut Edits,
) -> Result<(), CellError> {
    let text = &model.text;
    let body = format!(
        "{{{}}}",
        keys.iter()
            .map(|(k, e)| format!("{}: {}", key_text(k), flow_map(e)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    match root.get("sensors") {
        Some(s) if matches!(s.content, Content::Mapping(_)) => {
            add_to_mapping(edits, text, s, name, &body)
        }
        // `sensors:` with nothing after it (null)
        Some(s) => edits.replace(
            s,
            format!(
                "{}{{{name}: {body}}}",
                if s.start == s.end { " " } else { "" }
            ),
        ),
        None => add_to_mapping(edits, text, root, "sensors", &format!("{{{name}: {body}}}")),
    }
    Ok(())
}
