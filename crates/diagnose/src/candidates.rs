//! Candidate terms: every catalog term the declared model lacks that the machine family admits
//! and the recording's signals can inform, each as a family of variants (series orders, screw
//! leads, lag time constants, sensors and directions). Nothing here knows what wrote the
//! recording: sensors, axes and travels come from the model file and the records.
//!
//! Parameters of a variant are either *linear* (they enter the selection as Jacobian columns
//! about zero) or fixed at the variant's value (a lead, a τ: found by trying the grid, then
//! refined by the final nonlinear refit). Which linear parameters the data can separate from the
//! declared ones is decided later, on the columns ([`crate::candidate_columns`]).

use std::collections::{BTreeMap, BTreeSet};

use metrocell_model::{MachineGeometry, MachineKinematics};
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, ConfigValue, TermConfig, TermId};

use crate::signal_inventory::SignalInventory;

/// Where a candidate goes in the forward model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// A machine term (machine- or tool-frame displacement, or a kinematic term of the family).
    Machine,
    /// An instrument term of the tracker (warm-up, refraction).
    Instrument,
}

/// One variant of a candidate term.
#[derive(Debug, Clone)]
pub struct TermVariant {
    /// What distinguishes it (`order 2`, `lead 10 mm`, `z, τ = 20 min`), or "".
    pub name: String,
    /// The term as it would be written in the model file; its params are the values the
    /// columns are taken at (0 for linear parameters).
    pub config: TermConfig,
    /// Per term parameter (in the term's order): true if it enters the selection linearly.
    pub linear: Vec<bool>,
    /// Parameters fixed by the variant (lead, τ), counted by the information criterion.
    pub profiled: usize,
    /// Effectively different values compared to find the variant's fixed value (see
    /// [`crate::selection::Variant::search_multiplicity`]); 1 for a value from a fixed list.
    pub search_multiplicity: f64,
}

/// A candidate term instance and its variants.
#[derive(Debug, Clone)]
pub struct TermFamily {
    /// Instance label (`backlash[y]`), unique in the augmented model.
    pub label: String,
    pub id: TermId,
    pub placement: Placement,
    pub variants: Vec<TermVariant>,
}

/// A catalog term that was not tried, and why.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NotTried {
    pub term: String,
    pub reason: String,
}

/// Ball-screw leads tried for a cyclic error (m): the ISO 3408 preferred leads and the common
/// metric ones (the periodogram of the residuals adds its own peak).
pub const COMMON_LEADS_MM: [f64; 14] = [
    2.0, 2.5, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0, 25.0, 32.0, 40.0, 50.0,
];

/// Shortest time span of the readings over which an instrument's drift is tried (s).
pub const MIN_DRIFT_SPAN_S: f64 = 600.0;

/// Time constants tried for a structure's lag behind its sensor and for a tracker's warm-up (s).
/// The lag grid steps by √2: at a large effect a coarser grid leaves a misfit of the lag's shape
/// that a smooth empirical correction would then fit better than the physics (the refit refines
/// τ anyway; the grid decides which term is named).
pub const LAG_GRID_S: [f64; 15] = [
    120.0, 170.0, 240.0, 340.0, 480.0, 680.0, 960.0, 1360.0, 1920.0, 2720.0, 3840.0, 5430.0,
    7680.0, 10860.0, 15360.0,
];
pub const WARMUP_GRID_S: [f64; 9] = [
    300.0, 600.0, 1200.0, 1800.0, 2700.0, 3600.0, 5400.0, 7200.0, 10800.0,
];

fn text(s: &str) -> ConfigValue {
    ConfigValue::Text(s.into())
}
fn num(x: f64) -> ConfigValue {
    ConfigValue::Number(x)
}
fn list(v: Vec<ConfigValue>) -> ConfigValue {
    ConfigValue::List(v)
}
const AXES: [&str; 3] = ["x", "y", "z"];

fn config(id: TermId, options: Vec<(&str, ConfigValue)>, params: Vec<(String, f64)>) -> TermConfig {
    TermConfig {
        id: id.as_str().into(),
        options: options
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
        params: params
            .into_iter()
            .map(|(k, v)| (k, num(v)))
            .collect::<BTreeMap<_, _>>(),
        use_defaults: false,
    }
}

/// The configured parameter names of a term config (in the term's order).
fn param_names(c: &TermConfig) -> Option<Vec<String>> {
    let mut probe = c.clone();
    probe.use_defaults = true;
    probe.params.clear();
    configure(&probe)
        .ok()
        .map(|t| t.term.params().into_iter().map(|p| p.name).collect())
}

/// A variant whose parameters are all linear and start at zero.
fn linear_variant(
    name: impl Into<String>,
    id: TermId,
    options: Vec<(&str, ConfigValue)>,
) -> Option<TermVariant> {
    let mut c = config(id, options, vec![]);
    let names = param_names(&c)?;
    c.params = names.iter().map(|n| (n.clone(), num(0.0))).collect();
    let linear = vec![true; names.len()];
    Some(TermVariant {
        name: name.into(),
        config: c,
        linear,
        profiled: 0,
        search_multiplicity: 1.0,
    })
}

/// A variant with some parameters fixed at given values (the rest linear, at zero).
fn profiled_variant(
    name: impl Into<String>,
    id: TermId,
    options: Vec<(&str, ConfigValue)>,
    fixed: &[(&str, f64)],
) -> Option<TermVariant> {
    let mut v = linear_variant(name, id, options)?;
    let names = param_names(&v.config)?;
    for (n, value) in fixed {
        let k = names.iter().position(|x| x == n)?;
        v.config.params.insert(n.to_string(), num(*value));
        v.linear[k] = false;
    }
    v.profiled = fixed.len();
    Some(v)
}

fn family(
    variants: Vec<Option<TermVariant>>,
    id: TermId,
    placement: Placement,
) -> Option<TermFamily> {
    let variants: Vec<TermVariant> = variants.into_iter().flatten().collect();
    let first = variants.first()?;
    let label = configure(&first.config).ok()?.term.label();
    Some(TermFamily {
        label,
        id,
        placement,
        variants,
    })
}

/// What the candidates need to know about the declared model.
pub struct Declared<'a> {
    pub machine: &'a MachineGeometry,
    pub machine_terms: &'a TermModel,
    pub instrument_terms: &'a TermModel,
}

impl Declared<'_> {
    fn labels(&self) -> BTreeSet<String> {
        self.machine_terms
            .terms
            .iter()
            .chain(&self.instrument_terms.terms)
            .map(|t| t.term.label())
            .collect()
    }
    fn has(&self, id: TermId) -> bool {
        self.machine_terms
            .terms
            .iter()
            .chain(&self.instrument_terms.terms)
            .any(|t| t.term.id() == id)
    }
}

/// The lever axes of an angular error of `axis` on a cartesian machine: the axes between the
/// rotating carriage and the tool (tool side: the axes it carries; workpiece side: the tool
/// point's whole position relative to the table, as crates/physics `angular` documents).
fn lever_axes(machine: &MachineGeometry, axis: usize) -> Vec<usize> {
    match &machine.kinematics {
        MachineKinematics::Cartesian(order) => {
            let tool: Vec<usize> = order.tool_side.iter().map(|a| a.index()).collect();
            match tool.iter().position(|&a| a == axis) {
                Some(i) => tool[i + 1..].to_vec(),
                None => vec![0, 1, 2],
            }
        }
        // the five-axis linear chain (crates/kinematics `five_axis`, DH rows Y = d1, X = d2,
        // Z = d3): Y carries X carries Z, so each lever holds the axes it carries
        MachineKinematics::FiveAxis(_) => match axis {
            1 => vec![0, 2],
            0 => vec![2],
            _ => vec![],
        },
        _ => vec![],
    }
}

/// Every candidate family for the declared model and the signals the records hold, and the
/// catalog terms not tried with the reason. `periodogram_leads[k]` adds a lead found in the
/// residuals of axis k, with the number of independent periods the periodogram compared;
/// `points_in_machine_frame`: the records' points are in the machine (part) frame rather than
/// an instrument's.
///
/// The families are gathered in this order (the selection's tie-breaks see it): each axis's
/// geometry and thermal scale, the structure's thermal growth, motion, load and tool, the
/// family's kinematic terms, the instrument's terms, the part's terms; then those the declared
/// model already has are dropped.
pub fn candidate_families(
    declared: &Declared,
    inventory: &SignalInventory,
    periodogram_leads: &[Option<(f64, f64)>; 3],
    points_in_machine_frame: bool,
) -> (Vec<TermFamily>, Vec<NotTried>) {
    let machine = declared.machine;
    let mut out = Gathered::default();
    let axis_family = matches!(
        machine.kinematics,
        MachineKinematics::Cartesian(_) | MachineKinematics::FiveAxis(_)
    );
    if axis_family {
        axis_families(&mut out, machine, inventory, periodogram_leads);
    }
    thermal_growth_families(&mut out, inventory);
    motion_load_and_tool_families(&mut out, inventory, axis_family);
    kinematic_families(&mut out, machine, inventory);
    instrument_families(&mut out, declared, inventory);
    part_families(&mut out, declared, inventory, points_in_machine_frame);
    let labels = declared.labels();
    out.families.retain(|f| {
        !(labels.contains(&f.label)
            || f.id == TermId::ToolOffset && declared.has(TermId::ToolOffset))
    });
    (out.families, out.not_tried)
}

/// The candidate families gathered so far, and the catalog terms not tried with the reason.
#[derive(Default)]
struct Gathered {
    families: Vec<TermFamily>,
    not_tried: Vec<NotTried>,
}

impl Gathered {
    fn add(&mut self, family: Option<TermFamily>) {
        self.families.extend(family);
    }
    fn skip(&mut self, term: &str, reason: String) {
        self.not_tried.push(NotTried {
            term: term.into(),
            reason,
        })
    }
}

/// A family of one variant.
fn single(name: &str, id: TermId, options: Vec<(&str, ConfigValue)>) -> Option<TermFamily> {
    family(
        vec![linear_variant(name, id, options)],
        id,
        Placement::Machine,
    )
}

/// The travel of axis `k` as a term option.
fn travel(machine: &MachineGeometry, k: usize) -> ConfigValue {
    list(vec![num(machine.travel[k][0]), num(machine.travel[k][1])])
}

/// The geometry and thermal scale of each commanded axis of a cartesian or five-axis machine:
/// positioning of every axis, squareness of each pair, then per axis its straightness, angular
/// errors, cyclic screw error, backlash and thermal scale.
fn axis_families(
    out: &mut Gathered,
    machine: &MachineGeometry,
    inventory: &SignalInventory,
    periodogram_leads: &[Option<(f64, f64)>; 3],
) {
    for k in 0..3 {
        if !inventory.positions[k] {
            out.skip(
                &format!("geometry of axis {}", AXES[k]),
                format!("no commanded {} position in the records", AXES[k]),
            );
            continue;
        }
        let variants = (1..=3)
            .map(|o| {
                linear_variant(
                    format!("order {o}"),
                    TermId::Positioning,
                    vec![
                        ("axis", text(AXES[k])),
                        ("order", num(o as f64)),
                        ("travel", travel(machine, k)),
                    ],
                )
            })
            .collect();
        out.add(family(variants, TermId::Positioning, Placement::Machine));
    }
    for (pair, driver) in [("xy", 1), ("xz", 2), ("yz", 2)] {
        if inventory.positions[driver] {
            out.add(single("", TermId::Squareness, vec![("pair", text(pair))]));
        }
    }
    for k in 0..3 {
        if !inventory.positions[k] {
            continue;
        }
        straightness_families(out, machine, k);
        angular_families(out, machine, inventory, k);
        out.add(pitch_cyclic_family(machine, k, periodogram_leads[k]));
        if inventory.approach_both[k] {
            out.add(single("", TermId::Backlash, vec![("axis", text(AXES[k]))]));
        } else {
            out.skip(&format!("backlash[{}]", AXES[k]), format!("needs both directions of approach on {} (approach.{} columns, or commanded joint states the approach can be derived from)", AXES[k], AXES[k]));
        }
        thermal_scale_family(out, machine, inventory, k);
    }
}

/// The straightness of axis `k` along each other axis, orders 1–3.
fn straightness_families(out: &mut Gathered, machine: &MachineGeometry, k: usize) {
    for j in 0..3 {
        if j == k {
            continue;
        }
        let variants = (1..=3)
            .map(|o| {
                linear_variant(
                    format!("order {o}"),
                    TermId::Straightness,
                    vec![
                        ("axis", text(AXES[k])),
                        ("direction", text(AXES[j])),
                        ("order", num(o as f64)),
                        ("travel", travel(machine, k)),
                    ],
                )
            })
            .collect();
        out.add(family(variants, TermId::Straightness, Placement::Machine));
    }
}

/// The angular errors of axis `k` about each axis, orders 1–2, with the Abbe levers of the
/// stacking order (tried only when every lever axis is commanded).
fn angular_families(
    out: &mut Gathered,
    machine: &MachineGeometry,
    inventory: &SignalInventory,
    k: usize,
) {
    for a in 0..3 {
        let lever = lever_axes(machine, k);
        if lever.iter().any(|&l| !inventory.positions[l]) {
            continue;
        }
        let abbe = list(machine.tool_offset.iter().map(|v| num(*v)).collect());
        let variants = (1..=2)
            .map(|o| {
                linear_variant(
                    format!("order {o}"),
                    TermId::Angular,
                    vec![
                        ("axis", text(AXES[k])),
                        ("about", text(AXES[a])),
                        (
                            "lever_axes",
                            list(lever.iter().map(|l| text(AXES[*l])).collect()),
                        ),
                        ("abbe_offset", abbe.clone()),
                        ("order", num(o as f64)),
                        ("travel", travel(machine, k)),
                    ],
                )
            })
            .collect();
        out.add(family(variants, TermId::Angular, Placement::Machine));
    }
}

/// The cyclic screw error of axis `k`: the common leads shorter than a third of the travel, and
/// the residuals' own periodogram peak (`periodogram_lead`: lead, periods compared).
fn pitch_cyclic_family(
    machine: &MachineGeometry,
    k: usize,
    periodogram_lead: Option<(f64, f64)>,
) -> Option<TermFamily> {
    let span = machine.travel[k][1] - machine.travel[k][0];
    // the periodogram's own peak, unless a common lead lies within its resolution
    // (lead² / span: over 800 mm a 16 mm lead is resolved to 0.3 mm) — a screw's lead is
    // a catalog value, and a peak a little off it only fits the noise
    let leads: Vec<(f64, f64)> = COMMON_LEADS_MM
        .iter()
        .map(|l| (l * 1e-3, 1.0))
        .filter(|(l, _)| *l < span / 3.0)
        .chain(periodogram_lead.filter(|(l, _)| {
            !COMMON_LEADS_MM
                .iter()
                .any(|x| (x * 1e-3 - l).abs() < l * l / span.max(*l))
        }))
        .collect();
    let lead_mm = |l: f64| {
        format!("{:.4}", l * 1e3)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    };
    let variants = leads
        .iter()
        .map(|&(l, searched)| {
            profiled_variant(
                format!("lead {} mm", lead_mm(l)),
                TermId::PitchCyclic,
                vec![
                    ("axis", text(AXES[k])),
                    ("lead", num(l)),
                    ("harmonics", num(1.0)),
                ],
                &[],
            )
            .map(|mut v| {
                v.profiled = 1;
                v.search_multiplicity = searched;
                v
            })
        })
        .collect();
    family(variants, TermId::PitchCyclic, Placement::Machine)
}

/// The scale of axis `k` with each sensor, or each ordered pair at the two ends of the travel.
fn thermal_scale_family(
    out: &mut Gathered,
    machine: &MachineGeometry,
    inventory: &SignalInventory,
    k: usize,
) {
    let t = &inventory.temperatures;
    let mut variants = Vec::new();
    for s in t {
        variants.push(linear_variant(
            format!("sensor {s}"),
            TermId::ThermalScale,
            vec![
                ("axis", text(AXES[k])),
                ("sensors", list(vec![sensor(s, machine.travel[k][0])])),
            ],
        ));
    }
    for a in t {
        for b in t {
            if a != b {
                variants.push(linear_variant(
                    format!("sensors {a} → {b}"),
                    TermId::ThermalScale,
                    vec![
                        ("axis", text(AXES[k])),
                        (
                            "sensors",
                            list(vec![
                                sensor(a, machine.travel[k][0]),
                                sensor(b, machine.travel[k][1]),
                            ]),
                        ),
                    ],
                ));
            }
        }
    }
    if variants.is_empty() {
        out.skip(&format!("thermal_scale[{}]", AXES[k]), "no temperature sensor in the records (temperature/<sensor> topics or temperature.<sensor> columns)".into());
    }
    out.add(family(variants, TermId::ThermalScale, Placement::Machine));
}

/// The structure's growth: each sensor, along each axis, without lag or lagging by τ on a grid.
fn thermal_growth_families(out: &mut Gathered, inventory: &SignalInventory) {
    if inventory.temperatures.is_empty() {
        out.skip(
            "thermal_growth",
            "no temperature sensor in the records".into(),
        );
    }
    for s in &inventory.temperatures {
        let mut variants = Vec::new();
        for (k, dir) in AXES.iter().enumerate() {
            let direction = list(
                (0..3)
                    .map(|i| num(if i == k { 1.0 } else { 0.0 }))
                    .collect(),
            );
            variants.push(linear_variant(
                format!("along {dir}"),
                TermId::ThermalGrowth,
                vec![("sensor", text(s)), ("direction", direction.clone())],
            ));
            if inventory.histories.contains(s) {
                for tau in LAG_GRID_S {
                    variants.push(profiled_variant(
                        format!("along {dir}, lag τ = {:.0} min", tau / 60.0),
                        TermId::ThermalGrowth,
                        vec![
                            ("sensor", text(s)),
                            ("direction", direction.clone()),
                            ("lag", ConfigValue::Bool(true)),
                        ],
                        &[("time_constant", tau)],
                    ));
                }
            }
        }
        out.add(family(variants, TermId::ThermalGrowth, Placement::Machine));
    }
}

/// A time offset (records taken while moving), the compliance of each commanded axis under a
/// load, and the tool offset.
fn motion_load_and_tool_families(
    out: &mut Gathered,
    inventory: &SignalInventory,
    axis_family: bool,
) {
    if inventory.moving {
        out.add(single("", TermId::TimeOffset, vec![]));
    } else {
        out.skip("time_offset", "no record was taken while an axis moved (needs axis velocities: velocity.<axis> columns or joint-state velocities)".into());
    }
    if inventory.load && axis_family {
        for k in 0..3 {
            if inventory.positions[k] {
                out.add(single(
                    "",
                    TermId::Compliance,
                    vec![("extension_axis", text(AXES[k]))],
                ));
            }
        }
    } else if axis_family {
        out.skip("compliance", "no load force in the records".into());
    }
    out.add(single("", TermId::ToolOffset, vec![]));
}

/// The terms of the machine's family: a delta's rods, radius, towers and endstops; an arm's
/// joint offsets, link lengths and gravity terms; a five-axis table's rotary axis location.
fn kinematic_families(out: &mut Gathered, machine: &MachineGeometry, inventory: &SignalInventory) {
    match &machine.kinematics {
        MachineKinematics::Delta(_) => {
            for id in [
                TermId::DeltaRodLength,
                TermId::DeltaRadius,
                TermId::DeltaTowerAngle,
                TermId::DeltaEndstop,
            ] {
                out.add(single("", id, vec![]));
            }
        }
        MachineKinematics::SerialArm(arm) => {
            out.add(single(
                "",
                TermId::JointOffset,
                vec![("joints", num(arm.chain.dof() as f64))],
            ));
            out.add(single(
                "",
                TermId::LinkLength,
                vec![("links", num(arm.link_count() as f64))],
            ));
            match gravity_families(arm, inventory) {
                Ok(families) => out.families.extend(families),
                Err(reason) => {
                    for term in ["joint_compliance", "joint_backlash", "column_bending"] {
                        out.skip(term, reason.clone());
                    }
                }
            }
        }
        MachineKinematics::FiveAxis(f) => {
            if inventory.rotary[1] && inventory.rotary[2] {
                let v3 = |v: &nalgebra::Vector3<f64>| list(v.iter().map(|x| num(*x)).collect());
                let opts = vec![
                    ("b_pivot", v3(&f.geometry.b_pivot)),
                    ("c_offset", v3(&f.geometry.c_offset)),
                    ("workpiece_offset", v3(&f.geometry.workpiece_offset)),
                ];
                out.add(single("", TermId::RotaryAxisLocation, opts));
            } else {
                out.skip(
                    "rotary_axis_location",
                    "no B and C angles in the records".into(),
                );
            }
        }
        MachineKinematics::Cartesian(_) => {}
    }
}

/// The instrument's terms the declared model lacks: the tracker's warm-up, the instrument's
/// drift in time, the touch probe's pretravel, refraction with station air.
fn instrument_families(out: &mut Gathered, declared: &Declared, inventory: &SignalInventory) {
    if !declared.has(TermId::TrackerWarmup) {
        match inventory.power_on {
            Some((lo, hi)) => {
                let variants = WARMUP_GRID_S
                    .iter()
                    .filter(|&&tau| tau < 3.0 * hi.max(1.0) && tau > 0.05 * (hi - lo))
                    .map(|&tau| {
                        let mut v = profiled_variant(format!("τ = {:.0} min", tau / 60.0), TermId::TrackerWarmup, vec![], &[("time_constant", tau)]);
                        if let Some(v) = v.as_mut() {
                            // the constant range offset A: a fixed option of a tracker, tried with B
                            v.linear[0] = true;
                        }
                        v
                    })
                    .collect();
                out.add(family(variants, TermId::TrackerWarmup, Placement::Instrument));
            }
            None => out.skip("tracker_warmup", "no time since power-on in the records (the tracker's power-on time: /tracker/power_on, or an instrument_on_time column)".into()),
        }
    }
    // the instrument's pose drifting in time (a stand sinking, a head turning): low orders only,
    // so a drift that cycles stays for the empirical corrections to show
    if !declared.has(TermId::InstrumentDrift) && inventory.point_readings {
        match inventory.time_span {
            Some((lo, hi)) if hi - lo >= MIN_DRIFT_SPAN_S => {
                let span = list(vec![num(lo), num(hi)]);
                let variants = [(1, false, "linear, translation"), (1, true, "linear, translation and rotation"), (2, false, "quadratic, translation"), (2, true, "quadratic, translation and rotation")]
                    .into_iter()
                    .map(|(order, rotation, name)| linear_variant(name, TermId::InstrumentDrift, vec![("order", num(order as f64)), ("span", span.clone()), ("rotation", ConfigValue::Bool(rotation))]))
                    .collect();
                out.add(family(variants, TermId::InstrumentDrift, Placement::Instrument));
            }
            _ => out.skip("instrument_drift", format!("the readings span less than {:.0} min (or carry no time): a drift of the instrument needs readings spread over time", MIN_DRIFT_SPAN_S / 60.0)),
        }
    }
    // the touch probe's pretravel: a constant mean, the lobing of a kinematic probe's
    // three-point seat (n = 3) and the vertical pretravel
    if inventory.probe_hits && !declared.has(TermId::ProbePretravel) {
        out.add(family(
            vec![linear_variant(
                "3 lobes",
                TermId::ProbePretravel,
                vec![("lobes", num(3.0))],
            )],
            TermId::ProbePretravel,
            Placement::Instrument,
        ));
    }
    if !declared.has(TermId::Refraction) {
        if inventory.air {
            out.add(family(
                vec![profiled_variant(
                    "",
                    TermId::Refraction,
                    vec![],
                    &[("path_pressure_offset", 0.0)],
                )
                .map(|mut v| {
                    v.profiled = 0;
                    v
                })],
                TermId::Refraction,
                Placement::Instrument,
            ));
        } else {
            out.skip(
                "refraction",
                "no station air (temperature, pressure, humidity) in the records".into(),
            );
        }
    }
}

/// The part: its expansion about the workpiece origin with each temperature (the clamp point is
/// not known; expansion about another point differs by a shift growing with the same
/// temperature, which a thermal growth candidate covers), and a misalignment of the part's
/// frame. Only points taken in the part's (machine) frame show them: an instrument registered to
/// the part sights the tool, and a uniform scale or turn of its frame is the same as its own
/// pose, or its range scale.
fn part_families(
    out: &mut Gathered,
    declared: &Declared,
    inventory: &SignalInventory,
    points_in_machine_frame: bool,
) {
    if !points_in_machine_frame {
        for id in [TermId::WorkpieceExpansion, TermId::FrameMisalignment] {
            if !declared.has(id) {
                out.skip(id.as_str(), "the points are in an instrument frame registered to the part: a change of the part's frame or scale is the instrument's own pose or range scale there; points measured in the part's frame (probe hits, a CMM export) show it".into());
            }
        }
    } else if !declared.has(TermId::WorkpieceExpansion) {
        for s in &inventory.temperatures {
            out.add(single(
                "",
                TermId::WorkpieceExpansion,
                vec![("sensor", text(s))],
            ));
        }
    }
    if points_in_machine_frame && !declared.has(TermId::FrameMisalignment) {
        out.add(single("", TermId::FrameMisalignment, vec![]));
    }
}

/// The gravity terms of a robot whose URDF gives its masses: each revolute joint's compliance
/// and backlash (one family each, every revolute joint its parameter), a lifting column's bending
/// (each prismatic joint: it carries the arm), the links' expansion with each temperature sensor.
/// Err with the reason when the model names an accelerometer on the base whose readings the
/// recording lacks: the terms need the gravity it measures (tilted ground).
fn gravity_families(
    arm: &metrocell_model::SerialArm,
    inventory: &SignalInventory,
) -> Result<Vec<TermFamily>, String> {
    let mut out = Vec::new();
    if !arm.chain.joints.iter().any(|j| j.inertial.is_some()) {
        return Ok(out);
    }
    if let Some(a) = arm
        .accelerometers
        .iter()
        .find(|a| a.base_from_sensor.is_some())
        .filter(|_| !inventory.gravity_measured)
    {
        return Err(format!(
            "the model's base accelerometer `{}` (link {}) has no reading at every record: the gravity torques need the base's tilt it measures (record /imu/{}, or import columns accel.{}.x|y|z; without sensors.accelerometers the base is taken as level)",
            a.name, a.link, a.name, a.name
        ));
    }
    let names = arm.chain.variable_names();
    let revolute: Vec<ConfigValue> = names
        .iter()
        .zip(&arm.revolute)
        .filter(|(_, r)| **r)
        .map(|(n, _)| text(n))
        .collect();
    // the joints gravity loads most (RMS torque over the records at least a quarter of the
    // largest): a joint that carries little cannot show its compliance, and six free
    // compliances where two matter fit the noise and fail on held-out blocks
    let tau = &inventory.gravity_torque_rms;
    let largest = names
        .iter()
        .enumerate()
        .filter(|(k, _)| arm.revolute[*k])
        .filter_map(|(k, _)| tau.get(k))
        .cloned()
        .fold(0.0, f64::max);
    let loaded: Vec<ConfigValue> = names
        .iter()
        .enumerate()
        .filter(|(k, _)| {
            arm.revolute[*k]
                && tau
                    .get(*k)
                    .is_some_and(|t| largest > 0.0 && *t >= 0.25 * largest)
        })
        .map(|(_, n)| text(n))
        .collect();
    if !revolute.is_empty() {
        for id in [TermId::JointCompliance, TermId::JointBacklash] {
            let mut variants = vec![linear_variant(
                "revolute joints",
                id,
                vec![("joints", list(revolute.clone()))],
            )];
            if !loaded.is_empty() && loaded.len() < revolute.len() {
                variants.push(linear_variant(
                    "the joints gravity loads most",
                    id,
                    vec![("joints", list(loaded.clone()))],
                ));
            }
            out.extend(family(variants, id, Placement::Machine));
        }
    }
    for (name, _) in names.iter().zip(&arm.revolute).filter(|(_, r)| !**r) {
        out.extend(family(
            vec![linear_variant(
                "",
                TermId::ColumnBending,
                vec![("joint", text(name))],
            )],
            TermId::ColumnBending,
            Placement::Machine,
        ));
    }
    for s in &inventory.temperatures {
        out.extend(family(
            vec![linear_variant(
                "",
                TermId::LinkThermalExpansion,
                vec![("sensor", text(s))],
            )],
            TermId::LinkThermalExpansion,
            Placement::Machine,
        ));
    }
    Ok(out)
}

fn sensor(name: &str, position: f64) -> ConfigValue {
    ConfigValue::Map(
        [
            ("name".to_string(), text(name)),
            ("position".to_string(), num(position)),
        ]
        .into_iter()
        .collect(),
    )
}
