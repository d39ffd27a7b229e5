//! The diagnosis of one recording against one model, start to end (a library function: the
//! `metrocell diagnose` command calls it on the records of its bags, and a node can call it on a
//! sliding window of records). [`diagnose`] runs the stages in order, each a function of its own:
//!
//! 1–2. records made ready and the declared model fitted ([`crate::declared_stage`]);
//! 3. the declared model's residuals tested against noise and located ([`crate::locate`]);
//! 4. what the selection runs on and the candidates it chooses among ([`crate::candidate_stage`]);
//! 5. forward selection judged on held-out blocks ([`crate::selection`]) — or, as a baseline,
//!    every candidate at once ([`crate::all_at_once`]);
//! 6. the augmented model and its nonlinear refit ([`crate::augmented_stage`]);
//! 7. before/after on held-out blocks, honest σ, each found term's significance
//!    ([`crate::judgement`]) — a term whose effect is not ≥ 3σ from zero after the refit is
//!    dropped and the rest refitted;
//! 8. the noise the verdicts rely on and what remains;
//! 9. the findings in words ([`crate::findings`]), with what a value outside its usual range most
//!    likely means and the alternatives the recording cannot tell apart.

use std::collections::BTreeMap;

use metrocell_estimation::{FitError, FitOptions, MeasurementRecord, RecordFrame, RecordSet};
use metrocell_model::{ForwardModel, MachineGeometry, ParameterSetup};
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, ConfigValue, PhysicsError, TermConfig};
use nalgebra::Vector3;

use crate::all_at_once::all_at_once;
use crate::augmented_stage::Augmented;
use crate::candidate_stage::{candidates, Prepared, SelectionFrame};
use crate::candidates::{NotTried, Placement};
use crate::declared_stage::{declared_stage, DeclaredStage};
use crate::findings::{self, FoundTerm};
use crate::judgement::{judge, JudgeInputs, Judged};
use crate::locate::{locate, LocateOptions};
use crate::noise_tests::noise_report;
use crate::outliers::robust_scale;
use crate::report::*;
use crate::residual_view::ResidualView;
use crate::selection::{
    select_families, Family, FamilySelection, SelectionOptions, WhitenedData,
    MIN_SIGNIFICANCE_SIGMA,
};

/// The model the user declared.
pub struct DeclaredModel<'a> {
    pub machine: &'a MachineGeometry,
    pub machine_terms: &'a TermModel,
    /// As the model-file loader's rule gives them (crates/model_file `instrument_terms`: a
    /// `tracker_pose` always, the instruments' declared terms after it).
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

/// Says on stderr what is being done and how long it took (with `DiagnoseOptions::progress`).
pub(crate) struct Progress {
    on: bool,
    clock: std::time::Instant,
}

impl Progress {
    fn new(on: bool) -> Self {
        Self {
            on,
            clock: std::time::Instant::now(),
        }
    }
    pub(crate) fn say(&self, what: &str) {
        if self.on {
            eprintln!(
                "diagnose: {:7.2} s  {what}",
                self.clock.elapsed().as_secs_f64()
            );
        }
    }
}

/// Run the diagnosis: the stages in order, each a function of its own (the module's doc says
/// what each does).
///
/// 1–2. `declared_stage`: the records made ready, the declared model (with the tracker pose
///      its readings need) fitted; `DeclaredFit`: that fit's model, values and residuals;
/// 3. `located_before`: the declared model's residuals tested against noise and located;
/// 4. `selection_frame_and_candidates`: what the selection runs on, and the candidates;
/// 5. `select`: forward selection on held-out blocks (or every candidate at once);
/// 6–7. `refit_and_judge`: the augmented model refitted and judged, terms not significant
///      after the refit dropped;
/// 8. `noise_levels` and `what_remains`: the noise the verdicts rely on, what remains;
/// 9. `report`: the findings, the report, the augmented model's terms and the plots.
pub fn diagnose(
    declared: &DeclaredModel,
    records: &RecordSet,
    options: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let progress = Progress::new(options.progress);
    let stage = declared_stage(declared, records, options, &progress)?;
    let fitted = DeclaredFit::new(declared, &stage)?;
    progress.say("declared model fitted; testing and locating its residuals");
    let (samples0, located0) = located_before(&fitted, &stage, options);
    let (frame, prepared, not_tried) =
        selection_frame_and_candidates(declared, &fitted, &stage, options, &progress)?;
    let families: Vec<Family> = prepared.iter().map(|p| p.family.clone()).collect();
    let selection = select(&frame, &families, options, &progress);
    let mut messages = selection_messages(&selection, &families);
    let inputs = JudgeInputs {
        machine: declared.machine,
        declared_model: &fitted.model,
        stage: &stage,
        x0: &fitted.x0,
        free0: &fitted.free0,
        view0: &fitted.view0,
        folds_time: &frame.folds_time,
        folds_space: &frame.folds_space,
        selection: &selection,
        families: &families,
        prepared: &prepared,
        alpha: options.selection.alpha,
    };
    let (aug, x1, judged) = refit_and_judge(declared, &inputs, options, &mut messages, &progress)?;
    progress.say(&judged.uncertainty.statement);
    let (noise_rms, noise) = noise_levels(&stage, &judged);
    let (remaining, located1) = what_remains(&stage, &judged, &noise, options);
    progress.say("findings");
    let context = Context {
        located0: &located0,
        samples0: &samples0,
        selection: &selection,
        families: &families,
        not_tried,
        remaining,
        located1,
        noise_rms,
        noise,
        selection_records: frame.records.len(),
        options,
        view0: &fitted.view0,
    };
    report(
        declared, &stage, &aug, &x1, judged, context, messages, &progress,
    )
}

/// The declared model at its fit: the model (with the stage's instrument terms), its values,
/// the indices of its free parameters, and its residuals along the workpiece axes.
struct DeclaredFit<'a> {
    model: ForwardModel<'a>,
    x0: Vec<f64>,
    free0: Vec<usize>,
    view0: ResidualView,
}

impl<'a> DeclaredFit<'a> {
    fn new(declared: &DeclaredModel<'a>, stage: &'a DeclaredStage) -> Result<Self, DiagnoseError> {
        let model =
            ForwardModel::new(declared.machine, declared.machine_terms, &stage.instruments)?;
        let x0 = stage.fit.x.clone();
        let free0: Vec<usize> = stage
            .fit
            .parameters
            .iter()
            .enumerate()
            .filter(|(_, p)| p.free)
            .map(|(k, _)| k)
            .collect();
        let view0 = ResidualView::new(&model, &x0, &stage.set.records, &stage.set.frame)?;
        Ok(Self {
            model,
            x0,
            free0,
            view0,
        })
    }
}

/// Stage 3: the declared model's residual samples, and where they disagree with noise.
fn located_before(
    fitted: &DeclaredFit,
    stage: &DeclaredStage,
    options: &DiagnoseOptions,
) -> (
    Vec<crate::residual::ResidualSample>,
    Vec<crate::locate::Finding>,
) {
    let view0 = &fitted.view0;
    let before_wp: Vec<Vector3<f64>> = (0..view0.len()).map(|i| view0.workpiece(i)).collect();
    let samples0 = view0.samples(&stage.set.records, &before_wp);
    let located0 = locate(&samples0, &options.locate);
    (samples0, located0)
}

/// Stage 4: the records and columns the selection runs on, the candidates it chooses among, and
/// the catalog terms not tried with the reason.
fn selection_frame_and_candidates(
    declared: &DeclaredModel,
    fitted: &DeclaredFit,
    stage: &DeclaredStage,
    options: &DiagnoseOptions,
    progress: &Progress,
) -> Result<(SelectionFrame, Vec<Prepared>, Vec<NotTried>), DiagnoseError> {
    let (model, x0) = (&fitted.model, &fitted.x0);
    let frame = SelectionFrame::new(model, x0, &fitted.free0, stage, &fitted.view0, options)?;
    progress.say(&format!(
        "candidate columns on {} records",
        frame.records.len()
    ));
    let (prepared, not_tried) = candidates(declared, model, stage, x0, &frame, options)?;
    progress.say(&format!(
        "{} candidate families, {} variants; selecting",
        prepared.len(),
        prepared
            .iter()
            .map(|p| p.family.variants.len())
            .sum::<usize>()
    ));
    Ok((frame, prepared, not_tried))
}

/// Stage 5: the terms chosen among `families`, by forward selection on held-out blocks or, as a
/// baseline, every candidate at once.
fn select(
    frame: &SelectionFrame,
    families: &[Family],
    options: &DiagnoseOptions,
    progress: &Progress,
) -> FamilySelection {
    let data = WhitenedData {
        b: frame.b.clone(),
        declared: frame.declared_cols.clone(),
        folds: frame.folds.clone(),
    };
    let selection = match options.strategy {
        Strategy::Select => select_families(&data, families, &options.selection),
        Strategy::AllAtOnce => all_at_once(&data, families, options.selection.alpha),
    };
    progress.say(&format!(
        "selected {:?}; refitting the augmented model",
        selection
            .chosen
            .iter()
            .map(|c| c.label.as_str())
            .collect::<Vec<_>>()
    ));
    selection
}

/// What the selection has to say: the candidates refused for impossible values, and those chosen
/// early and replaced later.
fn selection_messages(selection: &FamilySelection, families: &[Family]) -> Vec<String> {
    let mut messages = refusals(selection, families);
    messages.extend(selection.swapped.iter().map(|(out, into)| format!("{out}, chosen early, was replaced by {into}: with the other terms in the model {into} explains the residuals better (lower BIC)")));
    messages
}

/// Stage 8: the RMS per coordinate the stated uncertainties predict (m), and which noise level
/// the verdicts rely on.
fn noise_levels(stage: &DeclaredStage, judged: &Judged) -> (f64, NoiseAssessment) {
    let noise_rms = (stage
        .set
        .records
        .iter()
        .map(|r| r.covariance.trace())
        .sum::<f64>()
        / (3 * stage.set.records.len()) as f64)
        .sqrt();
    let noise = assess_noise(
        stage.repeatability,
        robust_scale(&judged.whitened_after),
        judged.whitened_after.len(),
    );
    (noise_rms, noise)
}

/// Stages 6–7: the augmented model refitted and judged; while an added term's main parameters
/// are less than [`MIN_SIGNIFICANCE_SIGMA`] from zero after the refit (σ widened for correlated
/// residuals), the weakest is dropped, said, and the rest refitted.
fn refit_and_judge(
    declared: &DeclaredModel,
    inputs: &JudgeInputs,
    options: &DiagnoseOptions,
    messages: &mut Vec<String>,
    progress: &Progress,
) -> Result<(Augmented, Vec<f64>, Judged), DiagnoseError> {
    let mut chosen = inputs.selection.chosen.clone();
    loop {
        let aug = Augmented::new(
            declared.machine,
            declared.machine_terms,
            &inputs.stage.instruments,
            &inputs.stage.setup,
            &chosen,
            inputs.prepared,
        )?;
        let start = aug.start(declared.machine, inputs.declared_model, inputs.x0)?;
        let refit = aug.refit(
            declared.machine,
            &inputs.stage.set,
            inputs.view0,
            start,
            options,
        )?;
        let x1 = refit.x;
        progress.say("refitted; held-out before and after");
        let mut judged = judge(inputs, &aug, &x1)?;
        judged.at_bound = refit.at_bound;
        let weakest = judged
            .significance
            .iter()
            .filter(|(_, z)| *z < MIN_SIGNIFICANCE_SIGMA)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .cloned();
        match weakest {
            Some((label, z)) if options.strategy == Strategy::Select => {
                messages.push(format!(
                    "{label} was chosen on the linearised residuals, but after the refit its effect is only {z:.1}σ from zero (σ widened for correlated residuals and the refined nonlinear parameters): not significant, not reported as a finding"
                ));
                chosen.retain(|c| c.label != label);
            }
            _ => {
                messages.extend(refit.failure);
                messages.extend(judged.messages.iter().cloned());
                return Ok((aug, x1, judged));
            }
        }
    }
}

/// A candidate the data support best but whose values are impossible, said: nothing was named in
/// its place.
fn refusals(selection: &FamilySelection, families: &[Family]) -> Vec<String> {
    let mut out = Vec::new();
    for step in &selection.steps {
        let Some(f) = step.refused else { continue };
        let Some(score) = step.scores.iter().find(|s| s.label == families[f].label) else {
            continue;
        };
        let family = &families[f];
        let variant = family.variants.iter().find(|v| v.name == score.variant);
        let values: Vec<String> = variant
            .map(|v| {
                v.parameter_names
                    .iter()
                    .zip(&score.values)
                    .zip(&v.ranges)
                    .map(|((n, x), (lo, hi))| {
                        format!("{n} = {x:.4e} (possible {lo:.3e} … {hi:.3e})")
                    })
                    .collect()
            })
            .unwrap_or_default();
        out.push(format!(
            "{} would explain the residuals best (held-out gain {:.0} %, ΔBIC {:.0}) but needs {}, which is physically impossible; nothing is named in its place — check the recording's units, signs and time stamps, and the term's convention",
            family.label,
            100.0 * score.heldout_gain,
            score.delta_bic,
            values.join(", ")
        ));
    }
    out
}

/// Noise tests and localisation of the final residuals (against the stated σ, or the data's own
/// scale when that disagrees with it).
fn what_remains(
    stage: &DeclaredStage,
    judged: &Judged,
    noise: &NoiseAssessment,
    options: &DiagnoseOptions,
) -> (Vec<String>, Vec<crate::locate::Finding>) {
    let samples1 = judged.view1.samples(&stage.set.records, &judged.after_res);
    let rescaled: Vec<_> = if noise.basis == "stated" {
        samples1
    } else {
        samples1
            .into_iter()
            .map(|s| crate::residual::ResidualSample {
                sigma: s.sigma * noise.scale,
                ..s
            })
            .collect()
    };
    let report1 = noise_report(&rescaled, 8);
    let mut remaining: Vec<String> = report1
        .iter()
        .flat_map(|c| {
            c.tests
                .iter()
                .filter(|t| t.p_adjusted <= options.selection.alpha)
                .map(move |t| {
                    format!(
                        "{} {}: {} test rejects (p = {:.1e} after correction), χ²/dof {:.2}",
                        c.channel,
                        crate::residual::axis_name(c.axis),
                        t.name,
                        t.p_adjusted,
                        c.chi2_per_dof
                    )
                })
        })
        .collect();
    let located1 = locate(&rescaled, &options.locate);
    remaining.extend(
        located1
            .iter()
            .take(10)
            .map(|f| format!("structure left: {}", f.describe())),
    );
    (remaining, located1)
}

/// What the report needs besides the stages' results.
struct Context<'a> {
    located0: &'a [crate::locate::Finding],
    samples0: &'a [crate::residual::ResidualSample],
    selection: &'a FamilySelection,
    families: &'a [Family],
    not_tried: Vec<crate::candidates::NotTried>,
    remaining: Vec<String>,
    located1: Vec<crate::locate::Finding>,
    noise_rms: f64,
    noise: NoiseAssessment,
    selection_records: usize,
    options: &'a DiagnoseOptions,
    view0: &'a ResidualView,
}

/// The check points (kept out of every fit) predicted by the declared model at its fit and by the
/// augmented model at its refit, each with the placements its fit points gave; None without
/// check points.
fn check_scores(
    declared: &DeclaredModel,
    stage: &DeclaredStage,
    aug: &Augmented,
    x1: &[f64],
) -> Result<Option<crate::report::CheckScores>, DiagnoseError> {
    if stage.set.check.is_empty() {
        return Ok(None);
    }
    let before_model =
        ForwardModel::new(declared.machine, declared.machine_terms, &stage.instruments)?;
    let before = metrocell_estimation::check_points::check_report_of(
        &before_model,
        &stage.fit.x,
        &stage.set.check,
    );
    let after_model = aug.model(declared.machine)?;
    let after =
        metrocell_estimation::check_points::check_report_of(&after_model, x1, &stage.set.check);
    Ok(Some(crate::report::CheckScores {
        declared: before.overall,
        augmented: after.overall,
        unpredicted: after.unpredicted.len(),
    }))
}

/// The findings, the augmented model's terms, the report and the plots.
#[allow(clippy::too_many_arguments)]
fn report(
    declared: &DeclaredModel,
    stage: &DeclaredStage,
    aug: &Augmented,
    x1: &[f64],
    judged: Judged,
    ctx: Context,
    mut messages: Vec<String>,
    progress: &Progress,
) -> Result<Diagnosis, DiagnoseError> {
    let model_aug = aug.model(declared.machine)?;
    let found = found_terms(aug);
    let set = &stage.set;
    let built = findings::build(&findings::Inputs {
        model: &model_aug,
        x: x1,
        free: &aug.setup.free,
        sigmas: &judged.sigmas,
        names: &judged.names,
        records: &set.records,
        view: &judged.view1,
        after: &judged.after_res,
        found: &found,
        located_before: ctx.located0,
        samples_before: ctx.samples0,
        significance: &judged.significance,
        alternatives: &findings::alternatives_of(ctx.selection, ctx.families),
        at_bound: &judged.at_bound,
    })?;
    let added_terms = added_terms(aug, x1, &judged);
    let unexplained = findings::unexplained(
        &judged.empirical,
        &judged.view1,
        &ctx.located1,
        &set.records,
    );
    let explained = unexplained.is_empty() && ctx.remaining.is_empty();
    messages.extend(findings::advice(
        ctx.selection,
        ctx.families,
        &set.records,
        declared.machine,
    ));
    let mut summary = findings::summary(
        &built.findings,
        &unexplained,
        &judged.before,
        &judged.after,
        ctx.noise_rms,
        explained,
    );
    let check = check_scores(declared, stage, aug, x1)?;
    if let Some(c) = &check {
        summary.push_str(&check_sentence(c));
    }
    let report = Report {
        noise_rms_m: ctx.noise_rms,
        noise: ctx.noise,
        before: judged.before.clone(),
        after: judged.after.clone(),
        findings: built.findings,
        unexplained,
        explained,
        summary,
        strategy: ctx.options.strategy.name().into(),
        records: record_summary(stage, ctx.selection_records),
        declared: declared_parameters(stage),
        located: ctx.located0.iter().take(20).map(|f| f.describe()).collect(),
        remaining: ctx.remaining,
        selection: step_summaries(ctx.selection, ctx.families),
        not_tried: ctx.not_tried,
        messages,
        uncertainty: judged.uncertainty.clone(),
        check,
    };
    let sigma_workpiece = set
        .records
        .iter()
        .enumerate()
        .map(|(i, r)| ctx.view0.workpiece_sigma(i, &r.covariance))
        .collect();
    let fitted = fitted_parameters(aug, x1, &judged);
    let plots = plot_data(set, judged, built.evidence);
    progress.say("done");
    Ok(Diagnosis {
        report,
        added_terms,
        plots,
        records: set.records.clone(),
        sigma_workpiece,
        fitted,
    })
}

/// The terms the augmented model adds (in the order chosen), then the declared ones it freed.
fn found_terms(aug: &Augmented) -> Vec<FoundTerm> {
    let mut found: Vec<FoundTerm> = aug
        .added
        .iter()
        .enumerate()
        .map(|(k, a)| FoundTerm {
            label: a.label.clone(),
            id: a.id,
            variant: a.variant.clone(),
            placement: a.placement,
            order: k,
            config: a.config.clone(),
        })
        .collect();
    for f in &aug.freed {
        let config = TermConfig {
            id: f.id.as_str().into(),
            ..Default::default()
        };
        found.push(FoundTerm {
            label: f.label.clone(),
            id: f.id,
            variant: "declared, freed".into(),
            placement: Placement::Instrument,
            order: found.len(),
            config,
        });
    }
    found
}

/// The summary's sentence on the check points kept out of the fit.
fn check_sentence(c: &crate::report::CheckScores) -> String {
    format!(
        " On the {} check points kept out of the fit: p95 horizontal {:.2} mm with the declared model, {:.2} mm with the found terms (p95 vertical {:.2} → {:.2} mm).",
        c.augmented.n,
        c.declared.p95_xy_m * 1e3,
        c.augmented.p95_xy_m * 1e3,
        c.declared.p95_z_m * 1e3,
        c.augmented.p95_z_m * 1e3
    )
}

/// The records the diagnosis read, used, averaged and set aside (at most 50 rejections named).
fn record_summary(stage: &DeclaredStage, selection_records: usize) -> RecordSummary {
    let set = &stage.set;
    let mut rejected = stage.rejected.clone();
    rejected.truncate(50);
    RecordSummary {
        readings: stage.readings,
        used: set.records.len(),
        averaged_groups: stage.groups,
        rejected,
        outliers: stage.outlier_notes.clone(),
        frame: match &set.frame {
            RecordFrame::Machine => "machine".into(),
            RecordFrame::Instrument(f) => format!("instrument ({f})"),
        },
        selection_records,
    }
}

/// The declared model's free parameters after its own fit (placement parameters left out).
fn declared_parameters(stage: &DeclaredStage) -> BTreeMap<String, ParameterValue> {
    stage
        .fit
        .parameters
        .iter()
        .filter(|p| p.free && !metrocell_estimation::check_points::is_placement_parameter(&p.name))
        .map(|p| {
            (
                p.name.clone(),
                ParameterValue {
                    value: p.value,
                    sigma: p.sigma,
                    unit: p.unit.into(),
                    at_bound: p.at_bound.map(|b| b.name().to_string()),
                },
            )
        })
        .collect()
}

/// Every parameter of the augmented model after the final refit: name, value, and σ where it was
/// fitted.
fn fitted_parameters(
    aug: &Augmented,
    x1: &[f64],
    judged: &Judged,
) -> Vec<(String, f64, Option<f64>)> {
    judged
        .names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            (
                name.clone(),
                x1[k],
                if aug.setup.free[k] {
                    judged.sigmas[k]
                } else {
                    None
                },
            )
        })
        .collect()
}

/// The plots' data: residuals before and after, held-out residuals, the temperatures recorded at
/// every record, and each finding's evidence.
fn plot_data(
    set: &RecordSet,
    judged: Judged,
    evidence: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)>,
) -> PlotData {
    let n = set.records.len();
    let mut temperatures: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for r in &set.records {
        for (name, v) in &r.signals.temperatures {
            temperatures.entry(name.clone()).or_default().push(*v);
        }
    }
    temperatures.retain(|_, v| v.len() == n);
    PlotData {
        time: judged.view1.time,
        position: judged.view1.position,
        before: judged.before_res,
        after: judged.after_res,
        heldout_before: judged.held_before,
        heldout_after: judged.held_after,
        temperatures,
        evidence,
    }
}

/// The terms added to the model file: their configs with the fitted values, and the σ of the
/// fitted ones.
fn added_terms(aug: &Augmented, x1: &[f64], judged: &Judged) -> Vec<AddedTerm> {
    aug.added
        .iter()
        .map(|a| {
            let label = configure(&a.config)
                .map(|t| t.term.label())
                .unwrap_or_default();
            let mut c = a.config.clone();
            let mut sig = BTreeMap::new();
            for (k, name) in judged.names.iter().enumerate() {
                if let Some(p) = name.strip_prefix(&format!("{label}.")) {
                    c.params.insert(p.to_string(), ConfigValue::Number(x1[k]));
                    if let (Some(s), true) = (judged.sigmas[k], aug.setup.free[k]) {
                        sig.insert(p.to_string(), s);
                    }
                }
            }
            AddedTerm {
                config: c,
                sigmas: sig,
                placement: a.placement,
            }
        })
        .collect()
}

/// Which noise level the verdicts rely on: the stated one when the data's own measure agrees
/// with it within 25 % (or the data have none), else the data's.
fn assess_noise(
    repeatability: Option<(f64, usize)>,
    residual_scale: f64,
    residual_rows: usize,
) -> NoiseAssessment {
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
                .map(|c| StepScore {
                    label: c.label.clone(),
                    variant: c.variant.clone(),
                    heldout_gain: c.heldout_gain,
                    p_adjusted: c.wald_p_adjusted,
                    delta_bic: c.delta_bic,
                    plausible: c.plausible,
                    usual: c.usual,
                    significance_sigma: c.significance_sigma,
                    supported: c.supported,
                    separable: c.separable,
                    accepted: c.accepted,
                })
                .collect();
            top.sort_by(|a, b| b.heldout_gain.total_cmp(&a.heldout_gain));
            top.truncate(10);
            Step {
                chosen: s.chosen.map(|i| families[i].label.clone()),
                top,
            }
        })
        .collect()
}
