//! The diagnosis of one recording against one model, start to end (a library function: the
//! `metrocell diagnose` command calls it on the records of its bags, and a node can call it on a
//! sliding window of records):
//!
//! 1. records made ready ([`crate::record_preparation`]): unusable ones set aside with the
//!    reason, repeated readings of a stationary point averaged, their scatter kept as the
//!    recording's own measure of the noise;
//! 2. the declared model fitted (crates/estimation `fit`: registration, bounded robust
//!    Levenberg–Marquardt), so a mis-set declared parameter is not taken for missing physics;
//!    gross outliers set aside ([`crate::outliers`]) and the fit repeated;
//! 3. residuals tested against noise and located ([`crate::noise_tests`], [`crate::locate`]);
//! 4. candidate terms from the catalog ([`crate::candidates`]) with their Jacobian columns from
//!    the shared model at the declared fit ([`crate::candidate_columns`]), parameters the
//!    declared ones already explain set aside; empirical corrections ([`crate::empirical`]);
//! 5. forward selection judged on held-out blocks of time and of workspace with an F test and
//!    BIC ([`crate::selection`]) — or, as a baseline, every candidate at once;
//! 6. the augmented model refitted with the shared solver (nonlinear: lags, warm-up τ refined);
//! 7. before/after on held-out blocks, noise tests of what remains, and the findings in words
//!    ([`crate::findings`]).

use std::collections::BTreeMap;

use metrocell_estimation::{fit, FitError, FitOptions, MeasurementRecord, RecordFrame, RecordSet};
use metrocell_model::{ForwardModel, MachineGeometry, ParameterSetup};
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, ConfigValue, PhysicsError, TermConfig, TermId};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::blocked_least_squares::{pseudo_inverse, separable_columns, BaseFit, BlockedRows};
use crate::candidate_columns::ColumnContext;
use crate::candidates::{candidate_families, Declared, NotTried, Placement, TermFamily};
use crate::empirical::{bump_variants, time_variants, EmpiricalBasis};
use crate::findings::{self, FoundTerm};
use crate::folds::{time_blocks, workspace_blocks};
use crate::locate::{locate, LocateOptions};
use crate::noise_tests::noise_report;
use crate::outliers::{outliers, robust_scale};
use crate::periodogram::{independent_frequencies, strongest_period};
use crate::record_preparation::prepare;
use crate::report::*;
use crate::residual_view::ResidualView;
use crate::selection::{select_families, Family, FamilySelection, SelectionOptions, Variant, WhitenedData};

/// The model the user declared.
pub struct DeclaredModel<'a> {
    pub machine: &'a MachineGeometry,
    pub machine_terms: &'a TermModel,
    pub instrument_terms: &'a TermModel,
    /// Free/fixed and priors over the stacked parameters of machine + instrument terms.
    pub setup: &'a ParameterSetup,
}

/// How to choose terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// Greedy forward selection on held-out blocks (the method).
    Select,
    /// Every candidate at once by plain least squares, terms claimed where their parameters are
    /// significant (the baseline the method is compared with).
    AllAtOnce,
}

impl Strategy {
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Select => "select",
            Strategy::AllAtOnce => "all-at-once",
        }
    }
}

#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    pub strategy: Strategy,
    pub selection: SelectionOptions,
    pub fit: FitOptions,
    pub time_blocks: usize,
    pub workspace_blocks: usize,
    /// Average consecutive readings of one stationary point.
    pub average_repeats: bool,
    /// Largest gap between readings averaged together (s).
    pub repeat_gap_s: f64,
    /// Outlier threshold in robust scale units.
    pub outlier_threshold: f64,
    /// Longest record list the selection runs on (longer ones are thinned in time order for
    /// the selection only; the fits and before/after use every record).
    pub max_selection_records: usize,
    /// Try empirical corrections for structure no catalog term explains.
    pub empirical: bool,
    pub locate: LocateOptions,
    /// Say on stderr what is being done and how long each step took.
    pub progress: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            strategy: Strategy::Select,
            selection: SelectionOptions::default(),
            fit: FitOptions::default(),
            time_blocks: 5,
            workspace_blocks: 5,
            average_repeats: true,
            repeat_gap_s: 5.0,
            outlier_threshold: 12.0,
            max_selection_records: 12_000,
            empirical: true,
            locate: LocateOptions::default(),
            progress: false,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    #[error("no usable records: {0}")]
    NoRecords(String),
    #[error("too few measurements: {0}")]
    TooFew(String),
    #[error("the declared model cannot be fitted to the records: {0}")]
    DeclaredFit(FitError),
    #[error("the model: {0}")]
    Model(#[from] PhysicsError),
    #[error("the model does not fit the recording: {0}")]
    Mismatch(String),
}

/// A term added to the model, as it goes into the augmented model file.
#[derive(Debug, Clone)]
pub struct AddedTerm {
    pub config: TermConfig,
    /// Standard uncertainty of each fitted parameter (canonical unit).
    pub sigmas: BTreeMap<String, f64>,
    pub placement: Placement,
}

/// Per-record data for plots.
#[derive(Debug, Clone, Default)]
pub struct PlotData {
    pub time: Vec<f64>,
    pub position: Vec<Vector3<f64>>,
    /// Workpiece-frame residuals before (declared fit) and after (everything), m.
    pub before: Vec<Vector3<f64>>,
    pub after: Vec<Vector3<f64>>,
    /// Held-out residual norms per record (first scheme), m.
    pub heldout_before: Vec<f64>,
    pub heldout_after: Vec<f64>,
    /// Temperatures by sensor at each record.
    pub temperatures: BTreeMap<String, Vec<f64>>,
    /// For each finding (same order): signal and residual/fitted per record.
    pub evidence: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)>,
}

/// The diagnosis: the report, the terms to add to the model file, data for plots, the records
/// it used (after averaging repeats and setting outliers aside) with their stated σ along the
/// workpiece axes.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    pub report: Report,
    pub added_terms: Vec<AddedTerm>,
    pub plots: PlotData,
    pub records: Vec<MeasurementRecord>,
    pub sigma_workpiece: Vec<Vector3<f64>>,
    /// Every parameter of the augmented model after the final refit: `label.param`, value, and
    /// standard uncertainty where it was fitted and is identifiable (the model file's writer
    /// rewrites those).
    pub fitted: Vec<(String, f64, Option<f64>)>,
}

/// The declared model with a tracker pose (the model's reading needs one: free if the records
/// are in an instrument frame, the identity otherwise), and its setup.
fn with_tracker_pose(declared: &DeclaredModel) -> Result<(TermModel, ParameterSetup), PhysicsError> {
    let has_pose = declared.instrument_terms.terms.iter().any(|t| t.term.id() == TermId::TrackerPose);
    let mut instruments = TermModel::default();
    if !has_pose {
        instruments.push(configure(&TermConfig { id: "tracker_pose".into(), use_defaults: true, ..Default::default() })?)?;
    }
    for t in &declared.instrument_terms.terms {
        instruments.push(t.clone())?;
    }
    let model = ForwardModel::new(declared.machine, declared.machine_terms, &instruments)?;
    let setup = setup_by_name(&model, declared.setup, &|_| true);
    Ok((instruments, setup))
}

/// A setup for `model` taking free/fixed and priors from `old` by name; parameters `old` does
/// not know are free when `new_free(name)`.
fn setup_by_name(model: &ForwardModel, old: &ParameterSetup, new_free: &dyn Fn(&str) -> bool) -> ParameterSetup {
    let mut setup = ParameterSetup::all_free(model);
    for (k, name) in setup.names.clone().iter().enumerate() {
        match old.names.iter().position(|n| n == name) {
            Some(j) => {
                setup.free[k] = old.free[j];
                setup.priors[k] = old.priors[j];
            }
            None => setup.free[k] = new_free(name),
        }
    }
    setup
}

/// A candidate variant ready for the selection, with what it came from.
struct Prepared {
    family: Family,
    source: Source,
}

enum Source {
    Term { family: TermFamily, kept: Vec<Vec<usize>> },
    /// Declared parameters the model holds fixed, freed (`label.param` names).
    Freed { id: TermId, label: String, names: Vec<String> },
    Empirical(Vec<EmpiricalBasis>),
}

/// Empirical columns (whitened, records frame) of a basis for the records of `view`.
fn empirical_columns(view: &ResidualView, basis: &EmpiricalBasis) -> DMatrix<f64> {
    let k = basis.len();
    let mut out = DMatrix::zeros(3 * view.len(), k);
    let mut axis = Vector3::zeros();
    axis[basis.axis] = 1.0;
    let dir = view.rotation.transpose() * axis;
    for i in 0..view.len() {
        let w = view.whitening[i] * dir;
        for (j, v) in basis.values(view.time[i], &view.position[i]).iter().enumerate() {
            out.fixed_view_mut::<3, 1>(3 * i, j).copy_from(&(w * *v));
        }
    }
    out
}

fn expand_folds(per_record: &[usize]) -> Vec<usize> {
    per_record.iter().flat_map(|&f| [f, f, f]).collect()
}

/// Run the diagnosis.
pub fn diagnose(declared: &DeclaredModel, records: &RecordSet, options: &DiagnoseOptions) -> Result<Diagnosis, DiagnoseError> {
    let (instruments, setup) = with_tracker_pose(declared)?;
    let model = ForwardModel::new(declared.machine, declared.machine_terms, &instruments)?;
    let mut messages = Vec::new();
    let clock = std::time::Instant::now();
    let step = |what: &str| {
        if options.progress {
            eprintln!("diagnose: {:7.2} s  {what}", clock.elapsed().as_secs_f64());
        }
    };
    // 1. records
    let prep = prepare(&records.records, options.average_repeats, options.repeat_gap_s);
    let mut rejected: Vec<String> = records.rejected.iter().chain(&prep.rejected).map(|r| format!("{} ({}): {}", r.at, r.point_id, r.reason)).collect();
    if prep.records.is_empty() {
        return Err(DiagnoseError::NoRecords(if rejected.is_empty() { "the recording holds no measured points".into() } else { format!("every record was set aside: {}", rejected.iter().take(5).cloned().collect::<Vec<_>>().join("; ")) }));
    }
    let n_free = setup.free.iter().filter(|f| **f).count();
    let needed = (n_free + 10).div_ceil(3).max(12);
    if prep.records.len() < needed {
        return Err(DiagnoseError::TooFew(format!(
            "{} usable measured points for {} free declared parameters; needs at least {} points spread over the workspace (and over time) to fit the declared model and still hold some back to judge candidates",
            prep.records.len(),
            n_free,
            needed
        )));
    }
    let joints = declared.machine.joint_names();
    if let Some(r) = prep.records.iter().find(|r| r.q.len() != joints.len()) {
        return Err(DiagnoseError::Mismatch(format!(
            "the records carry {} joint values per point (point `{}` at t = {:.3} s), the model's machine has {} ({}): the recording is of another machine, or the model file is the wrong one",
            r.q.len(),
            r.point_id,
            r.time,
            joints.len(),
            joints.join(" ")
        )));
    }
    let mut set = RecordSet { frame: records.frame.clone(), records: prep.records.clone(), rejected: vec![], sources: records.sources.clone() };
    step(&format!("{} readings → {} records ({} groups of repeats averaged); fitting the declared model", prep.readings, prep.records.len(), prep.groups));
    // 2. declared fit, outliers, refit
    let mut declared_fit = fit(&model, &setup, &set, None, &options.fit).map_err(DiagnoseError::DeclaredFit)?;
    let mut outlier_notes = Vec::new();
    {
        let view = ResidualView::new(&model, &declared_fit.x, &set.records, &set.frame)?;
        let z: Vec<Vector3<f64>> = (0..view.len()).map(|i| view.whitening[i] * view.residual[i]).collect();
        let out = outliers(&z, &view.time, &view.position, options.outlier_threshold);
        if !out.is_empty() {
            let scatter = robust_scale(&z.iter().flat_map(|v| v.iter().copied()).collect::<Vec<_>>()).max(1e-12);
            for &i in &out {
                let r = &set.records[i];
                outlier_notes.push(format!("t = {:.1} s, point `{}` ({}): residual {:.1} µm, {:.0}× the robust scatter", r.time, r.point_id, r.channel, view.residual[i].norm() * 1e6, z[i].amax() / scatter));
            }
            let keep: Vec<MeasurementRecord> = set.records.iter().enumerate().filter(|(i, _)| !out.contains(i)).map(|(_, r)| r.clone()).collect();
            set.records = keep;
            declared_fit = fit(&model, &setup, &set, None, &options.fit).map_err(DiagnoseError::DeclaredFit)?;
        }
    }
    let n = set.records.len();
    let x0 = declared_fit.x.clone();
    {
        // a model of another machine leaves millimetres after its own fit
        let rms = metrocell_estimation::rms(&declared_fit.residuals_after);
        let noise = (set.records.iter().map(|r| r.covariance.trace()).sum::<f64>() / (3 * n) as f64).sqrt();
        if rms > 5e-4 && rms > 100.0 * noise {
            return Err(DiagnoseError::Mismatch(format!(
                "after fitting its own parameters the model still misses the measured points by {:.2} mm RMS ({:.0}× the stated noise of {:.1} µm): check the machine family and geometry, the tool offset, the instrument frame of the points, and the units of the recording",
                rms * 1e3,
                rms / noise,
                noise * 1e6
            )));
        }
    }
    let free0: Vec<usize> = declared_fit.parameters.iter().enumerate().filter(|(_, p)| p.free).map(|(k, _)| k).collect();
    let view0 = ResidualView::new(&model, &x0, &set.records, &set.frame)?;
    step("declared model fitted; testing and locating its residuals");
    // 3. where the declared model's residuals disagree with noise
    let before_wp: Vec<Vector3<f64>> = (0..n).map(|i| view0.workpiece(i)).collect();
    let samples0 = view0.samples(&set.records, &before_wp);
    let located0 = locate(&samples0, &options.locate);
    let located_text: Vec<String> = located0.iter().take(20).map(|f| f.describe()).collect();
    // folds per record: blocks of time, blocks of workspace
    let folds_time = time_blocks(&view0.time, options.time_blocks);
    let folds_space = workspace_blocks(&view0.position, options.workspace_blocks);
    // the records the selection runs on
    let stride = n.div_ceil(options.max_selection_records.max(1));
    let mut by_time: Vec<usize> = (0..n).collect();
    by_time.sort_by(|&a, &b| view0.time[a].total_cmp(&view0.time[b]));
    let sel_idx: Vec<usize> = by_time.iter().step_by(stride).copied().collect();
    let sel_records: Vec<MeasurementRecord> = sel_idx.iter().map(|&i| set.records[i].clone()).collect();
    let sel_view = ResidualView::new(&model, &x0, &sel_records, &set.frame)?;
    let mut ctx = ColumnContext::new(&model, &x0, &sel_records, &sel_view.whitening)?;
    let declared_cols = ctx.declared_columns(&free0)?;
    let b_sel = sel_view.whitened();
    let sel_folds = vec![expand_folds(&sel_idx.iter().map(|&i| folds_time[i]).collect::<Vec<_>>()), expand_folds(&sel_idx.iter().map(|&i| folds_space[i]).collect::<Vec<_>>())];
    step(&format!("candidate columns on {} records", sel_records.len()));
    // 4. candidates
    let inventory = crate::signal_inventory::SignalInventory::of(&sel_records);
    let mut leads = [None; 3];
    for (k, lead) in leads.iter_mut().enumerate() {
        if !inventory.positions[k] {
            continue;
        }
        let q: Vec<f64> = sel_records.iter().map(|r| r.signals.axis_position[k].unwrap_or(0.0)).collect();
        let res: Vec<f64> = (0..sel_view.len()).map(|i| sel_view.workpiece(i)[k]).collect();
        let w: Vec<f64> = sel_records.iter().map(|r| 1.0 / (sel_view.rotation * r.covariance * sel_view.rotation.transpose())[(k, k)]).collect();
        let span = declared.machine.travel[k][1] - declared.machine.travel[k][0];
        if span.is_finite() {
            let covered = q.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - q.iter().cloned().fold(f64::INFINITY, f64::min);
            *lead = strongest_period(&q, &res, &w, 1.5e-3, span / 3.0).map(|p| (p.0, independent_frequencies(covered, 1.5e-3, span / 3.0)));
        }
    }
    let decl = Declared { machine: declared.machine, machine_terms: declared.machine_terms, instrument_terms: &instruments };
    let (term_families, mut not_tried) = candidate_families(&decl, &inventory, &leads, set.frame == RecordFrame::Machine);
    let (declared_pinv, _) = pseudo_inverse(&declared_cols.tr_mul(&declared_cols));
    let mut prepared: Vec<Prepared> = Vec::new();
    for tf in term_families {
        let mut variants = Vec::new();
        let mut kept_all = Vec::new();
        let mut last_error = None;
        for v in &tf.variants {
            let cols = match ctx.columns(&v.config, tf.placement) {
                Ok(c) => c,
                Err(e) => {
                    last_error = Some(e.to_string());
                    continue;
                }
            };
            let specs = cols.term.term.params();
            let linear: Vec<usize> = (0..specs.len()).filter(|&j| v.linear[j]).collect();
            let sub = cols.columns.select_columns(&linear);
            let kept_local = separable_columns(&declared_pinv, &declared_cols, &sub);
            if kept_local.is_empty() {
                continue;
            }
            let kept: Vec<usize> = kept_local.iter().map(|&j| linear[j]).collect();
            variants.push(Variant {
                name: v.name.clone(),
                columns: cols.columns.select_columns(&kept),
                parameter_names: kept.iter().map(|&j| specs[j].name.clone()).collect(),
                units: kept.iter().map(|&j| specs[j].unit.to_string()).collect(),
                ranges: kept.iter().map(|&j| (specs[j].min, specs[j].max)).collect(),
                base_values: kept.iter().map(|&j| cols.term.params[j]).collect(),
                profiled: v.profiled,
                search_multiplicity: v.search_multiplicity,
            });
            kept_all.push(kept);
        }
        if variants.is_empty() {
            not_tried.push(NotTried { term: tf.label.clone(), reason: last_error.unwrap_or_else(|| "these records cannot separate it from the declared parameters (its effect is the same as theirs here)".into()) });
            continue;
        }
        // variants kept only where their columns were computed; keep configs aligned
        let kept_variants: Vec<_> = tf.variants.iter().filter(|v| variants.iter().any(|w| w.name == v.name)).cloned().collect();
        let family = TermFamily { variants: kept_variants, ..tf.clone() };
        prepared.push(Prepared { family: Family { label: tf.label.clone(), term: tf.id.as_str().into(), physical: true, variants, judged_by: None }, source: Source::Term { family, kept: kept_all } });
    }
    // a term the model declares but holds fixed at values the data may contradict: the air on
    // the beam (a model with a weather station declares refraction with no offset)
    let names0_all = model.param_names();
    for t in instruments.terms.iter().filter(|t| t.term.id() == TermId::Refraction) {
        let label = t.term.label();
        let name = format!("{label}.path_temperature_offset");
        let Some(k) = names0_all.iter().position(|n| *n == name) else { continue };
        if setup.free[k] {
            continue;
        }
        let cols = ctx.declared_columns(&[k])?;
        if separable_columns(&declared_pinv, &declared_cols, &cols).is_empty() {
            not_tried.push(NotTried { term: label.clone(), reason: "these records cannot separate the air's offset from the declared parameters".into() });
            continue;
        }
        let spec = &t.term.params()[0];
        let variant = Variant { name: "freed".into(), columns: cols, parameter_names: vec![spec.name.clone()], units: vec![spec.unit.into()], ranges: vec![(spec.min, spec.max)], base_values: vec![x0[k]], profiled: 0, search_multiplicity: 1.0 };
        prepared.push(Prepared { family: Family { label: label.clone(), term: TermId::Refraction.as_str().into(), physical: true, variants: vec![variant], judged_by: None }, source: Source::Freed { id: TermId::Refraction, label, names: vec![name] } });
    }
    if options.empirical {
        for axis in 0..3 {
            let res: Vec<f64> = (0..sel_view.len()).map(|i| sel_view.workpiece(i)[axis]).collect();
            let w: Vec<f64> = sel_records.iter().map(|r| 1.0 / (sel_view.rotation * r.covariance * sel_view.rotation.transpose())[(axis, axis)]).collect();
            // scheme 0 = blocks of time, 1 = blocks of workspace: each empirical shape is judged
            // on the scheme it can predict
            for (all_bases, judged_by) in [(time_variants(&sel_view.time, axis), 1usize), (bump_variants(&sel_view.position, &res, &w, axis), 0usize)] {
                // basis functions the declared parameters already span are left out
                let mut bases = Vec::new();
                let mut variants = Vec::new();
                for mut b in all_bases {
                    let cols = empirical_columns(&sel_view, &b);
                    let kept = separable_columns(&declared_pinv, &declared_cols, &cols);
                    if kept.is_empty() {
                        continue;
                    }
                    let columns = cols.select_columns(&kept);
                    if kept.len() < cols.ncols() {
                        b.kept = Some(kept);
                    }
                    variants.push(Variant { name: b.variant_name(), columns, parameter_names: (0..b.len()).map(|j| format!("c{j}")).collect(), units: vec!["m".into(); b.len()], ranges: vec![(-1.0, 1.0); b.len()], base_values: vec![0.0; b.len()], profiled: b.searched(), search_multiplicity: b.search_multiplicity() });
                    bases.push(b);
                }
                if bases.is_empty() {
                    continue;
                }
                prepared.push(Prepared { family: Family { label: bases[0].label(), term: "empirical".into(), physical: false, variants, judged_by: Some(vec![judged_by]) }, source: Source::Empirical(bases) });
            }
        }
    }
    step(&format!("{} candidate families, {} variants; selecting", prepared.len(), prepared.iter().map(|p| p.family.variants.len()).sum::<usize>()));
    // 5. selection
    let families: Vec<Family> = prepared.iter().map(|p| p.family.clone()).collect();
    let data = WhitenedData { b: b_sel.clone(), declared: declared_cols.clone(), folds: sel_folds };
    let selection = match options.strategy {
        Strategy::Select => select_families(&data, &families, &options.selection),
        Strategy::AllAtOnce => all_at_once(&data, &families, options.selection.alpha),
    };
    let steps = step_summaries(&selection, &families);
    step(&format!("selected {:?}; refitting the augmented model", selection.chosen.iter().map(|c| c.label.as_str()).collect::<Vec<_>>()));
    // 6. augmented model and its refit
    let mut machine_aug = declared.machine_terms.clone();
    let mut instruments_aug = instruments.clone();
    let mut added: Vec<(usize, TermConfig, Placement, Vec<String>, String)> = Vec::new();
    let mut freed: Vec<(usize, TermId, String, Vec<(String, f64)>)> = Vec::new();
    let mut empirical_chosen: Vec<(usize, EmpiricalBasis, Vec<f64>)> = Vec::new();
    for c in &selection.chosen {
        match &prepared[c.candidate].source {
            Source::Term { family, kept } => {
                let v = &family.variants[c.variant];
                let mut config = v.config.clone();
                for (name, value, _, _) in &c.parameters {
                    config.params.insert(name.clone(), ConfigValue::Number(*value));
                }
                let variant_name = v.name.clone();
                let term = configure(&config)?;
                let specs = term.term.params();
                let free_names: Vec<String> = kept[c.variant].iter().map(|&j| specs[j].name.clone()).chain(specs.iter().enumerate().filter(|(j, _)| !v.linear[*j] && v.profiled > 0 && family.id != TermId::Refraction).map(|(_, s)| s.name.clone())).collect();
                match family.placement {
                    Placement::Machine => machine_aug.push(term)?,
                    Placement::Instrument => instruments_aug.push(term)?,
                }
                added.push((c.candidate, config, family.placement, free_names, variant_name));
            }
            Source::Freed { id, label, names } => freed.push((c.candidate, *id, label.clone(), names.iter().cloned().zip(c.parameters.iter().map(|p| p.1)).collect())),
            Source::Empirical(bases) => {
                empirical_chosen.push((c.candidate, bases[c.variant].clone(), c.parameters.iter().map(|p| p.1).collect()));
            }
        }
    }
    let model_aug = ForwardModel::new(declared.machine, &machine_aug, &instruments_aug)?;
    let added_free: Vec<String> = added.iter().flat_map(|(_, config, _, free, _)| {
        let label = configure(config).map(|t| t.term.label()).unwrap_or_default();
        free.iter().map(move |p| format!("{label}.{p}"))
    }).collect();
    let mut setup_aug = setup_by_name(&model_aug, &setup, &|name| added_free.iter().any(|f| f == name));
    for (_, _, _, values) in &freed {
        for (name, _) in values {
            if let Some(k) = model_aug.param_names().iter().position(|n| n == name) {
                setup_aug.free[k] = true;
            }
        }
    }
    // start: the declared fit, the chosen terms at their selection values
    let names_aug = model_aug.param_names();
    let names0 = model.param_names();
    let mut start: Vec<f64> = model_aug.params();
    for (k, name) in names_aug.iter().enumerate() {
        if let Some(j) = names0.iter().position(|n| n == name) {
            start[k] = x0[j];
        }
        if let Some(v) = freed.iter().flat_map(|f| f.3.iter()).find(|(n, _)| n == name) {
            start[k] = v.1;
        }
    }
    // the empirical corrections are taken off the measurements while the physics is refitted
    let empirical_of = |view: &ResidualView, i: usize, list: &[(usize, EmpiricalBasis, Vec<f64>)]| -> Vector3<f64> {
        let mut d = Vector3::zeros();
        for (_, b, c) in list {
            d[b.axis] += b.value(c, view.time[i], &view.position[i]);
        }
        view.rotation.transpose() * d
    };
    let mut refit_set = set.clone();
    for (i, r) in refit_set.records.iter_mut().enumerate() {
        r.measured -= empirical_of(&view0, i, &empirical_chosen);
    }
    let final_fit = match fit(&model_aug, &setup_aug, &refit_set, Some(start.clone()), &options.fit) {
        Ok(f) => Some(f),
        Err(e) => {
            messages.push(format!("the nonlinear refit of the augmented model failed ({e}); the selection's linearised values are reported"));
            None
        }
    };
    let x1: Vec<f64> = final_fit.as_ref().map(|f| f.x.clone()).unwrap_or(start);
    step("refitted; held-out before and after");
    // 7. after: residual at x1 (empirical not yet subtracted) with the free columns of the
    // augmented model and the empirical columns, refitted linearly per held-out block
    let view1 = ResidualView::new(&model_aug, &x1, &set.records, &set.frame)?;
    let free1: Vec<usize> = setup_aug.free.iter().enumerate().filter(|(k, f)| **f && !(set.frame == RecordFrame::Machine && names_aug[*k].starts_with("tracker_pose."))).map(|(k, _)| k).collect();
    let mut ctx_all = ColumnContext::new(&model_aug, &x1, &set.records, &view1.whitening)?;
    let mut a1 = ctx_all.declared_columns(&free1)?;
    let emp_cols: Vec<DMatrix<f64>> = empirical_chosen.iter().map(|(_, b, _)| empirical_columns(&view1, b)).collect();
    for c in &emp_cols {
        let mut wide = DMatrix::zeros(a1.nrows(), a1.ncols() + c.ncols());
        wide.columns_mut(0, a1.ncols()).copy_from(&a1);
        wide.columns_mut(a1.ncols(), c.ncols()).copy_from(c);
        a1 = wide;
    }
    let row_folds = vec![expand_folds(&folds_time), expand_folds(&folds_space)];
    let rows = BlockedRows::new(&row_folds, 3 * n);
    let b1 = view1.whitened();
    let after_fit = BaseFit::new(&rows, rows.arrange(&a1), rows.arrange_vector(&b1));
    let ctx_before_cols = {
        let mut c0 = ColumnContext::new(&model, &x0, &set.records, &view0.whitening)?;
        c0.declared_columns(&free0)?
    };
    let before_fit = BaseFit::new(&rows, rows.arrange(&ctx_before_cols), rows.arrange_vector(&view0.whitened()));
    // the blockings every chosen term can be judged on
    let mut schemes: Vec<usize> = vec![0, 1];
    for c in &selection.chosen {
        if let Some(by) = &families[c.candidate].judged_by {
            schemes.retain(|s| by.contains(s));
        }
    }
    if schemes.is_empty() {
        messages.push("the empirical corrections in time and over the workspace cannot both be judged on held-out blocks; the held-out figures use both blockings".into());
        schemes = vec![0, 1];
    }
    let scheme_names: Vec<String> = schemes.iter().map(|&s| if s == 0 { "time".to_string() } else { "workspace".to_string() }).collect();
    let figures = |fitb: &BaseFit, view: &ResidualView| -> (FitFigures, Vec<Vector3<f64>>, Vec<f64>) {
        let held = fitb.heldout_residuals(&rows);
        let (mut ss, mut count, mut max) = (0.0, 0usize, 0.0f64);
        let mut first = vec![0.0; view.len()];
        for (s, h) in held.iter().enumerate() {
            if !schemes.contains(&s) {
                continue;
            }
            let e = view.to_workpiece_metres(&rows.restore_vector(h));
            for (i, v) in e.iter().enumerate() {
                ss += v.norm_squared();
                count += 3;
                max = max.max(v.norm());
                if s == schemes[0] {
                    first[i] = v.norm();
                }
            }
        }
        let full = view.to_workpiece_metres(&rows.restore_vector(&fitb.residuals()));
        let rms = (full.iter().map(|v| v.norm_squared()).sum::<f64>() / (3 * view.len()) as f64).sqrt();
        let dof = (fitb.rows() as f64 - fitb.rank() as f64).max(1.0);
        (FitFigures { heldout_rms_m: (ss / count.max(1) as f64).sqrt(), heldout_max_m: max, chi2_per_dof: fitb.ssr() / dof, rms_m: rms, heldout_blocks: scheme_names.clone() }, full, first)
    };
    let (before, before_res, held_before) = figures(&before_fit, &view0);
    let (after, after_res, held_after) = figures(&after_fit, &view1);
    // the empirical coefficients of the joint fit
    let sol = after_fit.solution();
    let cov = after_fit.unscaled_covariance();
    let dof1 = (after_fit.rows() as f64 - after_fit.rank() as f64).max(1.0);
    let sigma2 = after_fit.ssr() / dof1;
    // σ² of each column: the independent-rows figure, widened where the residuals are
    // correlated in time (crate::serial_correlation)
    let e1 = rows.restore_vector(&after_fit.residuals());
    let serial = crate::serial_correlation::sandwich(&a1, &e1, cov, &view1.time, after_fit.rank());
    let place = crate::serial_correlation::by_place(&a1, &e1, cov, &view1.position, after_fit.rank());
    // the choice of model: a candidate the data support (significant after correction, lower
    // BIC) that the last step declined only for its small held-out gain may still belong, and
    // whatever the found terms absorb of it is a bias no covariance shows. Each such
    // candidate's shift of the parameters (were it added to the final fit) counts in their σ
    // (the largest shift per parameter, added in quadrature)
    let mut shift2 = vec![0.0f64; a1.ncols()];
    let mut alternatives: Vec<(String, DVector<f64>)> = Vec::new();
    if let Some(last) = selection.steps.last().filter(|s| s.chosen.is_none()) {
        for sc in last.scores.iter().filter(|c| !c.accepted && c.separable && c.plausible && c.wald_p_adjusted <= options.selection.alpha && c.delta_bic < 0.0) {
            let Some(f) = families.iter().position(|f| f.label == sc.label) else { continue };
            let Some(vi) = families[f].variants.iter().position(|v| v.name == sc.variant) else { continue };
            let columns = match &prepared[f].source {
                Source::Term { family, kept } => match ctx_all.columns(&family.variants[vi].config, family.placement) {
                    Ok(c) => c.columns.select_columns(&kept[vi]),
                    Err(_) => continue,
                },
                Source::Empirical(bases) => empirical_columns(&view1, &bases[vi]),
                Source::Freed { .. } => continue,
            };
            let Some(d) = crate::serial_correlation::shift_if_added(&a1, &e1, cov, &columns) else { continue };
            for (j, v) in d.iter().enumerate() {
                shift2[j] = shift2[j].max(v * v);
            }
            let name = if sc.variant.is_empty() { sc.label.clone() } else { format!("{} ({})", sc.label, sc.variant) };
            alternatives.push((format!("{name}: p = {:.1e} after correction, ΔBIC {:.0}, held-out gain {:.3}", sc.wald_p_adjusted, sc.delta_bic, sc.heldout_gain), d));
        }
    }
    let variance = |j: usize| -> f64 {
        let classical = cov[(j, j)].max(0.0) * sigma2;
        let in_time = serial.as_ref().map_or(0.0, |s| s.covariance[(j, j)]);
        let in_place = place.as_ref().map_or(0.0, |s| s[(j, j)]);
        classical.max(in_time).max(in_place) + shift2[j]
    };
    let mut at = free1.len();
    let mut empirical_fitted = Vec::new();
    for (k, (_, basis, previous)) in empirical_chosen.iter().enumerate() {
        let len = emp_cols[k].ncols();
        let coefficients: Vec<f64> = (0..len).map(|j| previous[j] + sol[at + j]).collect();
        let sigmas: Vec<f64> = (0..len).map(|j| variance(at + j).sqrt()).collect();
        empirical_fitted.push((basis.clone(), coefficients, sigmas));
        at += len;
    }
    // noise: stated, or the data's own measure
    let noise_rms = (set.records.iter().map(|r| r.covariance.trace()).sum::<f64>() / (3 * n) as f64).sqrt();
    let whitened_after: Vec<f64> = rows.restore_vector(&after_fit.residuals()).iter().copied().collect();
    let residual_scale = robust_scale(&whitened_after);
    let noise = assess_noise(prep.repeatability_scale, residual_scale, whitened_after.len());
    // 8. what remains
    let samples1 = view1.samples(&set.records, &after_res);
    let rescaled: Vec<_> = if noise.basis == "stated" { samples1.clone() } else { samples1.iter().map(|s| crate::residual::ResidualSample { sigma: s.sigma * noise.scale, ..s.clone() }).collect() };
    let report1 = noise_report(&rescaled, 8);
    let mut remaining: Vec<String> = report1
        .iter()
        .flat_map(|c| c.tests.iter().filter(|t| t.p_adjusted <= options.selection.alpha).map(move |t| format!("{} {}: {} test rejects (p = {:.1e} after correction), χ²/dof {:.2}", c.channel, crate::residual::axis_name(c.axis), t.name, t.p_adjusted, c.chi2_per_dof)))
        .collect();
    let located1 = locate(&rescaled, &options.locate);
    remaining.extend(located1.iter().take(10).map(|f| format!("structure left: {}", f.describe())));
    step("findings");
    // 9. findings
    let mut found = Vec::new();
    for (k, (cand, config, placement, _, variant)) in added.iter().enumerate() {
        let label = configure(config)?.term.label();
        let Source::Term { family, .. } = &prepared[*cand].source else { unreachable!("terms only") };
        found.push(FoundTerm { label, id: family.id, variant: variant.clone(), placement: *placement, order: k, config: config.clone() });
    }
    for (_, id, label, _) in &freed {
        let config = TermConfig { id: id.as_str().into(), ..Default::default() };
        found.push(FoundTerm { label: label.clone(), id: *id, variant: "declared, freed".into(), placement: Placement::Instrument, order: found.len(), config });
    }
    let mut uncertainty = UncertaintyNote { blocks: serial.as_ref().map_or(0, |s| s.blocks), lag_blocks: serial.as_ref().map_or(0, |s| s.lag_blocks), place_clusters: place.is_some(), ..Default::default() };
    let found_labels: Vec<String> = found.iter().map(|f| format!("{}.", f.label)).collect();
    for (j, &k) in free1.iter().enumerate() {
        let classical = cov[(j, j)].max(0.0) * sigma2;
        if classical > 0.0 && variance(j) > classical && found_labels.iter().any(|l| names_aug[k].starts_with(l.as_str())) {
            uncertainty.widened.insert(names_aug[k].clone(), (variance(j) / classical).sqrt());
        }
    }
    let how = match (&serial, &place) {
        (None, None) => "with independent rows (too few records to measure their correlation)".to_string(),
        (Some(s), _) => format!(
            "widened where the residuals are correlated in time (scores summed over {} blocks of time, Newey–West over {} neighbouring blocks){}",
            s.blocks,
            s.lag_blocks,
            if place.is_some() { format!(" or at one place (scores clustered on a {0}×{0}×{0} grid over the workspace)", crate::serial_correlation::PLACE_CELLS) } else { String::new() }
        ),
        (None, Some(_)) => format!("widened where the residuals are correlated at one place (scores clustered on a {0}×{0}×{0} grid over the workspace)", crate::serial_correlation::PLACE_CELLS),
    };
    for (what, d) in &alternatives {
        let moved: Vec<String> = free1
            .iter()
            .enumerate()
            .filter(|(j, &k)| found_labels.iter().any(|l| names_aug[k].starts_with(l.as_str())) && d[*j] * d[*j] > 0.1 * cov[(*j, *j)].max(0.0) * sigma2)
            .map(|(j, &k)| format!("{} by {:+.3e}", names_aug[k], d[j]))
            .collect();
        if !moved.is_empty() {
            uncertainty.alternatives.push(format!("{what} — the data support it but the held-out test declined it; with it {}: counted in the σ", moved.join(", ")));
        }
    }
    let most = uncertainty.widened.iter().max_by(|a, b| a.1.total_cmp(b.1));
    uncertainty.statement = format!(
        "σ from the final fit's covariance, {how}{}",
        match most {
            Some((name, f)) => format!("; the correlation and the candidates the data support but the selection declined widen {} found parameters' σ, most {name} by {f:.2}×", uncertainty.widened.len()),
            None => "; nothing widens a found parameter's σ".into(),
        }
    );
    step(&uncertainty.statement);
    let sigmas1 = {
        // σ from the joint linear fit at the solution (pseudo-inverse: valid on the identifiable
        // directions even when a declared combination is not)
        let mut m = vec![None; names_aug.len()];
        for (j, &k) in free1.iter().enumerate() {
            m[k] = Some(variance(j).sqrt());
        }
        m
    };
    let built = findings::build(&findings::Inputs {
        model: &model_aug,
        x: &x1,
        free: &setup_aug.free,
        sigmas: &sigmas1,
        names: &names_aug,
        records: &set.records,
        view: &view1,
        after: &after_res,
        found: &found,
        located_before: &located0,
        samples_before: &samples0,
    })?;
    let added_terms: Vec<AddedTerm> = added
        .iter()
        .map(|(_, config, placement, _, _)| {
            let label = configure(config).map(|t| t.term.label()).unwrap_or_default();
            let mut c = config.clone();
            let mut sig = BTreeMap::new();
            for (k, name) in names_aug.iter().enumerate() {
                if let Some(p) = name.strip_prefix(&format!("{label}.")) {
                    c.params.insert(p.to_string(), ConfigValue::Number(x1[k]));
                    if let Some(s) = sigmas1[k] {
                        if setup_aug.free[k] {
                            sig.insert(p.to_string(), s);
                        }
                    }
                }
            }
            AddedTerm { config: c, sigmas: sig, placement: *placement }
        })
        .collect();
    let unexplained = findings::unexplained(&empirical_fitted, &view1, &after_res, &located1, &set.records);
    let explained = unexplained.is_empty() && remaining.is_empty();
    // declared parameters after their own fit
    let mut declared_params = BTreeMap::new();
    for p in declared_fit.parameters.iter().filter(|p| p.free && !p.name.starts_with("tracker_pose.")) {
        declared_params.insert(p.name.clone(), ParameterValue { value: p.value, sigma: p.sigma, unit: p.unit.into() });
    }
    messages.extend(findings::advice(&selection, &families, &set.records, declared.machine));
    rejected.truncate(50);
    let summary = findings::summary(&built.findings, &unexplained, &before, &after, noise_rms, explained);
    let report = Report {
        noise_rms_m: noise_rms,
        noise,
        before,
        after,
        findings: built.findings,
        unexplained,
        explained,
        summary,
        strategy: options.strategy.name().into(),
        records: RecordSummary { readings: prep.readings, used: n, averaged_groups: prep.groups, rejected, outliers: outlier_notes, frame: match &set.frame { RecordFrame::Machine => "machine".into(), RecordFrame::Instrument(f) => format!("instrument ({f})") }, selection_records: sel_records.len() },
        declared: declared_params,
        located: located_text,
        remaining,
        selection: steps,
        not_tried,
        messages,
        uncertainty,
    };
    let mut temperatures: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for r in &set.records {
        for (name, v) in &r.signals.temperatures {
            temperatures.entry(name.clone()).or_default().push(*v);
        }
    }
    temperatures.retain(|_, v| v.len() == n);
    let plots = PlotData { time: view1.time.clone(), position: view1.position.clone(), before: before_res, after: after_res, heldout_before: held_before, heldout_after: held_after, temperatures, evidence: built.evidence };
    step("done");
    let sigma_workpiece = set.records.iter().map(|r| view0.workpiece_sigma(&r.covariance)).collect();
    let fitted = names_aug.iter().enumerate().map(|(k, name)| (name.clone(), x1[k], if setup_aug.free[k] { sigmas1[k] } else { None })).collect();
    Ok(Diagnosis { report, added_terms, plots, records: set.records, sigma_workpiece, fitted })
}

/// Which noise level the verdicts rely on: the stated one when the data's own measure agrees
/// with it within 25 % (or the data have none), else the data's.
fn assess_noise(repeatability: Option<(f64, usize)>, residual_scale: f64, residual_rows: usize) -> NoiseAssessment {
    match repeatability {
        Some((s, dof)) if dof >= 30 => {
            if (0.8..=1.25).contains(&s) {
                NoiseAssessment { basis: "stated".into(), scale: s, dof, statement: format!("repeated readings scatter {s:.2}× their stated σ ({dof} degrees of freedom): the stated uncertainties are relied on") }
            } else {
                NoiseAssessment { basis: "repeatability".into(), scale: s, dof, statement: format!("repeated readings scatter {s:.2}× their stated σ ({dof} degrees of freedom): the stated uncertainties look {} and the verdicts use the scatter of the repeats instead", if s > 1.0 { "understated" } else { "overstated" }) }
            }
        }
        _ => {
            if (0.8..=1.25).contains(&residual_scale) {
                NoiseAssessment { basis: "stated".into(), scale: residual_scale, dof: residual_rows, statement: format!("no repeated readings; the final residuals scatter {residual_scale:.2}× the stated σ (robust): the stated uncertainties are relied on") }
            } else {
                NoiseAssessment { basis: "residual_scatter".into(), scale: residual_scale, dof: residual_rows, statement: format!("no repeated readings; the final residuals scatter {residual_scale:.2}× the stated σ (robust): the verdicts use that scatter, not the stated σ (selection never relies on the stated level: its tests use the residual variance)") }
            }
        }
    }
}

/// The selection steps in words and numbers (at most ten candidates each, best held-out gain
/// first).
fn step_summaries(selection: &FamilySelection, families: &[Family]) -> Vec<Step> {
    selection
        .steps
        .iter()
        .map(|s| {
            let mut top: Vec<StepScore> = s
                .scores
                .iter()
                .map(|c| StepScore { label: c.label.clone(), variant: c.variant.clone(), heldout_gain: c.heldout_gain, p_adjusted: c.wald_p_adjusted, delta_bic: c.delta_bic, plausible: c.plausible, separable: c.separable, accepted: c.accepted })
                .collect();
            top.sort_by(|a, b| b.heldout_gain.total_cmp(&a.heldout_gain));
            top.truncate(10);
            Step { chosen: s.chosen.map(|i| families[i].label.clone()), top }
        })
        .collect()
}

/// The baseline: every physical family's first variant and every declared column in one plain
/// least-squares fit; a term is claimed when its parameters are jointly significant (F test at
/// `alpha`, no correction for the number of terms), ordered by p-value.
pub fn all_at_once(data: &WhitenedData, families: &[Family], alpha: f64) -> FamilySelection {
    let physical: Vec<usize> = (0..families.len()).filter(|&f| families[f].physical).collect();
    let n = data.b.len();
    let mut widths = Vec::new();
    let total: usize = data.declared.ncols() + physical.iter().map(|&f| families[f].variants[0].columns.ncols()).sum::<usize>();
    let mut a = DMatrix::zeros(n, total);
    a.columns_mut(0, data.declared.ncols()).copy_from(&data.declared);
    let mut at = data.declared.ncols();
    for &f in &physical {
        let c = &families[f].variants[0].columns;
        a.columns_mut(at, c.ncols()).copy_from(c);
        widths.push((f, at, c.ncols()));
        at += c.ncols();
    }
    let rows = BlockedRows::new(&data.folds, n);
    let everything = BaseFit::new(&rows, rows.arrange(&a), rows.arrange_vector(&data.b));
    let before = BaseFit::new(&rows, rows.arrange(&data.declared), rows.arrange_vector(&data.b));
    let x = everything.solution();
    let cov = everything.unscaled_covariance();
    let dof = (n as f64 - everything.rank() as f64).max(1.0);
    let sigma2 = everything.ssr() / dof;
    let mut claimed: Vec<(f64, crate::selection::ChosenTerm)> = Vec::new();
    for &(f, start, k) in &widths {
        let xk = x.rows(start, k).into_owned();
        let ck = cov.view((start, start), (k, k)).into_owned() * sigma2;
        let (inv, rank) = pseudo_inverse(&ck);
        if rank < k {
            continue;
        }
        let stat = (xk.transpose() * inv * &xk)[0] / k as f64;
        let p = statrs::distribution::FisherSnedecor::new(k as f64, dof).map(|d| statrs::distribution::ContinuousCDF::sf(&d, stat)).unwrap_or(1.0);
        if p <= alpha {
            let v = &families[f].variants[0];
            let parameters = (0..k).map(|j| (v.parameter_names[j].clone(), v.base_values[j] + xk[j], ck[(j, j)].max(0.0).sqrt(), v.units[j].clone())).collect();
            claimed.push((p, crate::selection::ChosenTerm { candidate: f, variant: 0, label: families[f].label.clone(), term: families[f].term.clone(), physical: true, parameters }));
        }
    }
    claimed.sort_by(|a, b| a.0.total_cmp(&b.0));
    let restore = |v: Vec<DVector<f64>>| v.iter().map(|e| rows.restore_vector(e)).collect::<Vec<_>>();
    FamilySelection {
        chosen: claimed.into_iter().map(|c| c.1).collect(),
        steps: Vec::new(),
        dropped: Vec::new(),
        heldout_before: restore(before.heldout_residuals(&rows)),
        heldout_after: restore(everything.heldout_residuals(&rows)),
        residual_after: rows.restore_vector(&everything.residuals()),
        chi2_per_dof_before: before.ssr() / (n as f64 - before.rank() as f64).max(1.0),
        chi2_per_dof_after: everything.ssr() / dof,
        declared_increment: x.rows(0, data.declared.ncols()).into_owned(),
    }
}
