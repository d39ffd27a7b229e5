//! The diagnosis as data: what `metrocell diagnose --json` prints and the HTML report draws.
//! Field names are a contract with the tools that read them (the concealed-effect suite's
//! harness, dashboards): add fields, never rename. Units: SI (m, s, rad, 1/K …) in every `_m`,
//! `value` and `sigma` field; statements use µm, mm and minutes, as metrologists read them.

use std::collections::BTreeMap;

use metrocell_estimation::CheckStatistics;
use serde::Serialize;

use crate::candidates::NotTried;
use crate::empirical::EmpiricalBasis;

/// Held-out and in-sample figures of one model (before: the declared model refitted; after:
/// with the found terms and any empirical correction).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FitFigures {
    /// RMS per coordinate of the residuals of each block predicted by a fit to the other blocks
    /// (blocks of time and blocks of workspace, every record predicted once per scheme), m.
    pub heldout_rms_m: f64,
    /// Largest 3-D held-out residual, m.
    pub heldout_max_m: f64,
    /// χ² of the whitened residuals of the full-data fit per degree of freedom (1 = the stated
    /// noise).
    pub chi2_per_dof: f64,
    /// RMS per coordinate of the full-data fit's residuals, m.
    pub rms_m: f64,
    /// The blockings the held-out figures use (`time`, `workspace`): both, unless an empirical
    /// correction was added that one of them cannot judge (a correction in time cannot predict
    /// a held-out block of time); before and after use the same.
    pub heldout_blocks: Vec<String>,
}

/// A fitted parameter.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParameterValue {
    pub value: f64,
    /// Standard uncertainty (k = 1); null when not identifiable.
    pub sigma: Option<f64>,
    pub unit: String,
    /// `lower`/`upper` when the fit ended on that bound of the parameter's possible range: the
    /// data want a value beyond it, and `sigma` is no interior uncertainty; absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at_bound: Option<String>,
}

/// Where a structure lives.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct Where {
    /// Channels (instruments) whose residuals carry it.
    pub channels: Vec<String>,
    /// Workpiece axis along which it is largest (`x`, `y`, `z`), and its share of the effect.
    pub axis: String,
    /// Region, time window, direction of motion or condition where it is largest, in words.
    pub description: String,
    /// Localisation findings on the declared model's residuals this structure accounts for.
    pub located: Vec<String>,
}

/// One bin of evidence: the residual (with the term's own effect put back) against the term's
/// signal, and what the fitted term predicts there.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EvidenceBin {
    pub signal: f64,
    pub residual_m: f64,
    pub residual_sigma_m: f64,
    pub fitted_m: f64,
    pub count: usize,
}

/// The residual against the term's signal.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Evidence {
    /// What the signal is and its unit.
    pub signal: String,
    pub unit: String,
    /// Direction the residual is read along (`x`, `y`, `z`, or `line of sight`).
    pub along: String,
    pub bins: Vec<EvidenceBin>,
    /// Correlation of residual and fitted effect over the records.
    pub correlation: f64,
}

/// A named piece of physics the model left out, fitted.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Finding {
    /// Catalog id.
    pub term: String,
    /// Instance label in the augmented model.
    pub label: String,
    /// The variant the selection chose (order, lead, lag, sensors).
    pub variant: String,
    pub parameters: BTreeMap<String, ParameterValue>,
    #[serde(rename = "where")]
    pub location: Where,
    pub evidence: Evidence,
    /// One sentence with the numbers.
    pub statement: String,
    /// RMS of its effect on the records, m.
    pub effect_rms_m: f64,
    /// Its main parameters' joint distance from zero after the final fit, σ (≥ 3 for a finding).
    pub significance_sigma: f64,
    /// Parameters outside their usual range, each with what that most likely means in practice
    /// (empty: every value usual). Unusual values compete like any other; they are only said.
    pub unusual: Vec<String>,
    /// Other catalog terms this recording cannot tell from this one (BIC within 2, or fitted
    /// effects correlated beyond 0.95), with what measurement would separate them.
    pub alternatives: Vec<Alternative>,
}

/// A candidate the recording cannot tell from a finding.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Alternative {
    /// Catalog id and instance label.
    pub term: String,
    pub label: String,
    pub variant: String,
    /// Its BIC minus the finding's, when both were tried in the same step.
    pub delta_bic: f64,
    /// Correlation of its fitted effect with the finding's.
    pub correlation: f64,
    /// What would tell them apart.
    pub separated_by: String,
}

/// A structure no catalog term explains.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Unexplained {
    #[serde(rename = "where")]
    pub location: Where,
    /// The empirical correction fitted to it (no physical name), if one was accepted.
    pub correction: Option<EmpiricalCorrection>,
    pub statement: String,
}

/// An empirical correction: its basis and coefficients (m).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EmpiricalCorrection {
    pub label: String,
    #[serde(flatten)]
    pub basis: EmpiricalBasis,
    pub coefficients_m: Vec<f64>,
    pub coefficient_sigmas_m: Vec<f64>,
    pub effect_rms_m: f64,
    pub empirical: bool,
}

/// Which noise level the verdicts rely on.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct NoiseAssessment {
    /// `stated` (the records' covariances), `repeatability` (scatter of repeated readings),
    /// or `residual_scatter` (robust scatter of the final residuals).
    pub basis: String,
    /// Observed scatter ÷ stated σ by the data's own measure (repeats, or residuals).
    pub scale: f64,
    /// Degrees of freedom behind `scale`.
    pub dof: usize,
    pub statement: String,
}

/// One candidate's score in one selection step.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct StepScore {
    pub label: String,
    pub variant: String,
    pub heldout_gain: f64,
    pub p_adjusted: f64,
    pub delta_bic: f64,
    /// Every parameter inside its possible range (physics allows the values).
    pub plausible: bool,
    /// Every parameter inside its usual range (for the words only; never decides).
    pub usual: bool,
    /// The main parameters' distance from zero, σ (joint Wald, as a normal score).
    pub significance_sigma: f64,
    /// The data support it (held-out gain, F test, BIC, ≥ 3σ), whatever its values.
    pub supported: bool,
    pub separable: bool,
    pub accepted: bool,
}

/// One step of the selection.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Step {
    pub chosen: Option<String>,
    /// The best-scoring candidates of the step (by held-out gain), at most ten.
    pub top: Vec<StepScore>,
}

/// What the records were and what happened to them.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct RecordSummary {
    pub readings: usize,
    pub used: usize,
    pub averaged_groups: usize,
    pub rejected: Vec<String>,
    pub outliers: Vec<String>,
    pub frame: String,
    /// Records the selection ran on (all, or a thinning in time order of a long recording).
    pub selection_records: usize,
}

/// The whole diagnosis.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Report {
    /// RMS per coordinate the stated uncertainties predict, m.
    pub noise_rms_m: f64,
    pub noise: NoiseAssessment,
    pub before: FitFigures,
    pub after: FitFigures,
    /// Most important (largest effect) first.
    pub findings: Vec<Finding>,
    pub unexplained: Vec<Unexplained>,
    /// True when no structure is left unexplained by catalog physics and what remains after
    /// the found terms is consistent with noise.
    pub explained: bool,
    /// The answer in one paragraph.
    pub summary: String,
    pub strategy: String,
    pub records: RecordSummary,
    /// The declared model's free parameters after its own fit.
    pub declared: BTreeMap<String, ParameterValue>,
    /// Where the declared model's residuals disagree with noise (before anything is added).
    pub located: Vec<String>,
    /// Noise tests of the final residuals that reject, in words (empty: consistent with noise).
    pub remaining: Vec<String>,
    pub selection: Vec<Step>,
    pub not_tried: Vec<NotTried>,
    /// Advice: what to measure next, what could not be told apart.
    pub messages: Vec<String>,
    /// How the found terms' σ were made.
    pub uncertainty: UncertaintyNote,
    /// The recording's check points (`role: check`, kept out of every fit) as predicted by the
    /// declared model and by the model with the found terms; None without check points.
    pub check: Option<CheckScores>,
}

/// Check-point errors (predicted − measured, instrument frame; crates/estimation
/// `check_points` for the statistics) before and after the found terms.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CheckScores {
    pub declared: CheckStatistics,
    pub augmented: CheckStatistics,
    /// Check points neither model could predict (their setup has no pose…).
    pub unpredicted: usize,
}

/// How the σ of the found terms (and of the augmented model's parameters) were made: the
/// independent-rows covariance of the final joint fit, widened to the sandwich covariance where
/// the residuals are correlated in time or at one place (crate::serial_correlation).
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct UncertaintyNote {
    /// Consecutive blocks of time the scores were summed over (0: too few records, the
    /// independent-rows σ are reported).
    pub blocks: usize,
    /// Neighbouring blocks the sandwich counted (Bartlett lag window).
    pub lag_blocks: usize,
    /// Whether the scores were also clustered by place (a grid over the workspace).
    pub place_clusters: bool,
    /// Each found parameter (`label.param`) whose σ the correlation widened, by the factor
    /// σ(sandwich) / σ(independent rows).
    pub widened: BTreeMap<String, f64>,
    /// Candidates the data support (significant, lower BIC) that the last selection step
    /// declined for their small held-out gain, with how far each would move the found
    /// parameters: that shift is counted in their σ (the largest per parameter, in quadrature).
    pub alternatives: Vec<String>,
    pub statement: String,
}
