//! Naming what the model left out: greedy forward selection of candidate terms, judged on
//! held-out blocks.
//!
//! Each candidate *family* is a catalog term instance the model lacks (`backlash[y]`) — or an
//! empirical correction, which is never given a physical name — with one or more *variants*
//! (series orders, a screw lead, a lag time constant, a sensor pair), each given as the columns
//! of its Jacobian at each whitened residual row: how the prediction moves per unit of each of
//! its linear parameters. Around the declared fit the residual is linear in them, so each step
//! solves, for every remaining variant, the least-squares problem of the declared free
//! parameters, the terms chosen so far and the variant together
//! ([`crate::blocked_least_squares`]: column-scaled, rank-revealing, so a variant the data cannot
//! separate from what is already there is recognised as such).
//!
//! A variant is acceptable when, at once:
//! * it lowers the held-out error — the sum of squared whitened residuals of each block predicted
//!   by a fit to the other blocks, over blocks of time and blocks of workspace (never random
//!   rows) — by at least `min_cv_gain` of what it was;
//! * its parameters are significant: an F test of the SSR it explains against the residual
//!   variance the data show (so stated uncertainties that are off by a factor neither invent nor
//!   hide effects), Bonferroni-corrected over every variant tried in the step;
//! * its main parameters (the effect's, not a nuisance such as a warm-up's constant offset) are
//!   at least 3σ from zero (jointly, as the equivalent normal score of their Wald χ²);
//! * every parameter lies in the term's *possible* range (physics: no negative time constant);
//!   a value outside the *usual* range competes like any other and is only said so in words;
//! * the Bayesian information criterion n·ln(SSR/n) + k·ln n falls, with k counting the
//!   parameters a variant fixed by search (a lag τ, a screw lead) as well as the linear ones.
//!
//! A candidate the data support (held-out gain, F test, BIC, significance) but whose values are
//! impossible is *refused*; when a refused candidate is better (lower BIC by more than
//! [`TIE_BIC`]) than the best acceptable one, nothing is named in its place: the step stops and
//! the refusal is reported, so a worse physical name never stands in for a better impossible one.
//!
//! Among the acceptable, each family keeps its variant of lowest BIC and the family of lowest BIC
//! wins, physical terms first: an empirical correction wins only when its BIC is lower than the
//! best physical term's by more than `empirical_margin` (or 2 % of the physical term's own |ΔBIC|,
//! whichever is larger) (strong evidence that no catalog term
//! explains the structure as well). The loop stops when nothing is acceptable or `max_terms` were
//! added; then every chosen term is tested again given all the others (backward elimination), so
//! a term that only stood in for a later one is dropped.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

use crate::blocked_least_squares::{BaseFit, BlockedRows, CandidateFit};

/// One candidate, as columns over the residual rows (a family with a single variant; the form
/// used before variants existed, whitened by [`SelectionData::sigma`]).
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Instance label, e.g. `backlash[y]`.
    pub label: String,
    /// Catalog id, or `empirical` for a correction that carries no physical name.
    pub term: String,
    pub physical: bool,
    /// n × p: ∂prediction/∂parameter at each residual row (SI units).
    pub columns: DMatrix<f64>,
    pub parameter_names: Vec<String>,
    pub units: Vec<String>,
    /// Possible range of each parameter (the term's documented physical limits), SI.
    pub ranges: Vec<(f64, f64)>,
    /// Parameter values the columns were taken at (0 for a term the model lacks).
    pub base_values: Vec<f64>,
}

/// The parameters of a variant that carry its effect: `main` (indices into its columns; empty
/// = all) jointly at least [`MIN_SIGNIFICANCE_SIGMA`] from zero.
pub const MIN_SIGNIFICANCE_SIGMA: f64 = 3.0;

/// One variant of a family: its whitened columns and what they mean.
#[derive(Debug, Clone)]
pub struct Variant {
    /// What distinguishes it within the family (`order 2`, `lead 10 mm`, `τ = 20 min`), or "".
    pub name: String,
    /// n × p whitened columns, rows in the order of [`WhitenedData`].
    pub columns: DMatrix<f64>,
    pub parameter_names: Vec<String>,
    pub units: Vec<String>,
    /// Possible range of each parameter (outside it a value is impossible), SI.
    pub ranges: Vec<(f64, f64)>,
    /// Usual range of each parameter (for the words only), SI.
    pub usual: Vec<(f64, f64)>,
    /// The columns whose parameters carry the effect (a warm-up's B, not its constant offset A);
    /// empty: all. Their joint significance decides whether the variant can be named.
    pub main: Vec<usize>,
    pub base_values: Vec<f64>,
    /// Parameters fixed by a search over values (counted in the BIC).
    pub profiled: usize,
    /// How many effectively different values that search compared (the independent
    /// frequencies of a periodogram, the centres a bump was placed at; 1 for a value from a
    /// fixed list, whose members are variants of their own): the F test's p-value is multiplied
    /// by it and the BIC charged 2·ln of it, so the best of many tries is not mistaken for an
    /// effect.
    pub search_multiplicity: f64,
}

/// A candidate family.
#[derive(Debug, Clone)]
pub struct Family {
    pub label: String,
    pub term: String,
    pub physical: bool,
    pub variants: Vec<Variant>,
    /// The blocking schemes whose held-out error judges it (None: all). An empirical correction
    /// in time cannot predict a held-out block of time by construction, nor a local bump a
    /// held-out slab of workspace: each is judged on the other scheme.
    pub judged_by: Option<Vec<usize>>,
}

/// Which of two equally good physical explanations to name: where the data cannot tell them
/// apart (BIC within [`TIE_BIC`]), the conventional, simpler name — a linear x error along z is
/// reported as squareness, not as a first-order straightness or an angular error.
pub fn preference(term: &str) -> usize {
    const ORDER: [&str; 22] = [
        "squareness",
        "positioning",
        "backlash",
        "pitch_cyclic",
        "thermal_scale",
        "thermal_growth",
        "tracker_warmup",
        "refraction",
        "instrument_drift",
        "time_offset",
        "tool_offset",
        "column_bending",
        "joint_compliance",
        "joint_backlash",
        "link_thermal_expansion",
        "straightness",
        "compliance",
        "workpiece_expansion",
        "frame_misalignment",
        "rotary_axis_location",
        "angular",
        "probe_pretravel",
    ];
    ORDER.iter().position(|t| *t == term).unwrap_or(ORDER.len())
}

/// BIC difference below which two candidates count as equally supported (Kass & Raftery:
/// "not worth more than a bare mention").
pub const TIE_BIC: f64 = 2.0;

/// ΔBIC that counts as decisive evidence (Kass & Raftery: "very strong" beyond 10): what a swap
/// from a term at usual values to one at unusual values must gain.
const DECISIVE_BIC: f64 = 10.0;

/// BIC difference below which two candidates whose effects are confounded (correlated beyond
/// [`CONFOUNDED_CORRELATION`]) count as equally supported (Kass & Raftery: below "strong"): the
/// same effect at slightly different shapes (a positioning error and a scale with a sensor that
/// barely moves) is named by convention, the other kept as an alternative.
pub const CONFOUNDED_BIC: f64 = 6.0;

/// The data: residuals after the declared fit, their σ, the declared free parameters' Jacobian,
/// and fold assignments (one vector per blocking scheme, fold ids 0..k).
#[derive(Debug, Clone)]
pub struct SelectionData {
    pub residual: DVector<f64>,
    pub sigma: DVector<f64>,
    pub declared: DMatrix<f64>,
    pub folds: Vec<Vec<usize>>,
}

/// Whitened data: residual rows b, the declared free parameters' whitened Jacobian, and the fold
/// of each row in each blocking scheme.
#[derive(Debug, Clone)]
pub struct WhitenedData {
    pub b: DVector<f64>,
    pub declared: DMatrix<f64>,
    pub folds: Vec<Vec<usize>>,
}

#[derive(Debug, Clone)]
pub struct SelectionOptions {
    pub alpha: f64,
    pub min_cv_gain: f64,
    pub max_terms: usize,
    /// How much lower (BIC units) an empirical correction's BIC must be than the best physical
    /// term's to be preferred to it.
    pub empirical_margin: f64,
    /// The margin grows with the physical term's own support: an empirical correction must also
    /// beat it by this fraction of its |ΔBIC| (a physical term that explains 99 % of a large
    /// effect and misses the rest by its model's imperfection — a lag's exact shape — is still
    /// the physics; what it misses is judged in the next step).
    pub empirical_margin_relative: f64,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        Self {
            alpha: 0.01,
            min_cv_gain: 0.02,
            max_terms: 3,
            empirical_margin: 10.0,
            empirical_margin_relative: 0.02,
        }
    }
}

/// How one candidate (the best variant of a family, or a variant) fared in one step.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateScore {
    pub label: String,
    /// The variant's name ("" for a single-variant family).
    pub variant: String,
    /// Held-out sum of squared whitened residuals with the candidate added.
    pub heldout_ssr: f64,
    /// Relative fall of the held-out error on the schemes that judge it.
    pub heldout_gain: f64,
    pub wald_p_adjusted: f64,
    /// Every parameter inside its possible range (named `plausible` in the JSON contract).
    pub plausible: bool,
    /// Every parameter inside its usual range.
    pub usual: bool,
    /// The main parameters' distance from zero in σ (the equivalent normal score of their joint
    /// Wald χ²).
    pub significance_sigma: f64,
    /// The data support it (held-out gain, F test, BIC, significance), whatever its values.
    pub supported: bool,
    pub separable: bool,
    pub delta_bic: f64,
    pub values: Vec<f64>,
    pub sigmas: Vec<f64>,
    pub accepted: bool,
}

/// One step of the forward selection.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionStep {
    pub heldout_ssr_before: f64,
    /// One score per family: its acceptable variant of lowest BIC, else its variant of lowest BIC.
    pub scores: Vec<CandidateScore>,
    /// Index into the families (candidates) of the term added, if any.
    pub chosen: Option<usize>,
    /// A family the data support better than anything acceptable but whose values are
    /// impossible: the step named nothing in its place (index into the families).
    pub refused: Option<usize>,
    /// Other acceptable candidates this recording cannot tell from the one chosen.
    pub alternatives: Vec<StepAlternative>,
}

/// A candidate the recording cannot tell from the one a step chose: its BIC within
/// [`TIE_BIC`] of the chosen's, or its fitted effect correlated with the chosen's beyond
/// [`CONFOUNDED_CORRELATION`].
#[derive(Debug, Clone, PartialEq)]
pub struct StepAlternative {
    /// Index into the families, and of its variant.
    pub family: usize,
    pub variant: usize,
    /// Its BIC minus the chosen's (≥ 0 up to the tie rule).
    pub delta_bic: f64,
    /// Correlation of its fitted effect with the chosen's over the residual rows.
    pub correlation: f64,
}

/// Correlation of two candidates' fitted effects above which the recording cannot tell them
/// apart, whatever their BIC difference says about this particular noise draw.
pub const CONFOUNDED_CORRELATION: f64 = 0.95;

/// A chosen term with its fitted parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ChosenTerm {
    /// Index of the family (candidate) and of its variant.
    pub candidate: usize,
    pub variant: usize,
    pub label: String,
    pub term: String,
    pub physical: bool,
    /// (name, value, σ, unit).
    pub parameters: Vec<(String, f64, f64, String)>,
}

/// The outcome on whitened data.
#[derive(Debug, Clone)]
pub struct FamilySelection {
    pub chosen: Vec<ChosenTerm>,
    pub steps: Vec<SelectionStep>,
    /// Labels dropped by the backward pass.
    pub dropped: Vec<String>,
    /// (replaced, replacement) labels of the swaps after the forward steps.
    pub swapped: Vec<(String, String)>,
    /// Held-out whitened residual of every row, one vector per scheme, before and after.
    pub heldout_before: Vec<DVector<f64>>,
    pub heldout_after: Vec<DVector<f64>>,
    /// Full-data whitened residual after the selection.
    pub residual_after: DVector<f64>,
    /// SSR/(n − rank) of the declared fit and of the fit with the chosen terms.
    pub chi2_per_dof_before: f64,
    pub chi2_per_dof_after: f64,
    /// The fitted coefficients of the declared columns after the selection (increments to the
    /// declared fit).
    pub declared_increment: DVector<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    pub chosen: Vec<ChosenTerm>,
    pub steps: Vec<SelectionStep>,
    /// Held-out RMS of the whitened residuals before and after (1 = the stated noise).
    pub heldout_rms_z_before: f64,
    pub heldout_rms_z_after: f64,
    /// Held-out RMS of the residuals (m) before and after.
    pub heldout_rms_m_before: f64,
    pub heldout_rms_m_after: f64,
    pub heldout_max_m_before: f64,
    pub heldout_max_m_after: f64,
    /// χ²/dof of the full-data fit after selection.
    pub chi2_per_dof_after: f64,
}

/// Run the forward selection on single-variant candidates with per-row σ (whitening is r/σ).
pub fn select(
    data: &SelectionData,
    candidates: &[Candidate],
    options: &SelectionOptions,
) -> Selection {
    let whiten = |m: &DMatrix<f64>| {
        let mut w = m.clone();
        for (i, mut row) in w.row_iter_mut().enumerate() {
            row /= data.sigma[i];
        }
        w
    };
    let whitened = WhitenedData {
        b: data.residual.component_div(&data.sigma),
        declared: whiten(&data.declared),
        folds: data.folds.clone(),
    };
    let families: Vec<Family> = candidates
        .iter()
        .map(|c| Family {
            label: c.label.clone(),
            term: c.term.clone(),
            physical: c.physical,
            variants: vec![Variant {
                name: String::new(),
                columns: whiten(&c.columns),
                parameter_names: c.parameter_names.clone(),
                units: c.units.clone(),
                ranges: c.ranges.clone(),
                usual: c.ranges.clone(),
                main: Vec::new(),
                base_values: c.base_values.clone(),
                profiled: 0,
                search_multiplicity: 1.0,
            }],
            judged_by: None,
        })
        .collect();
    let s = select_families(&whitened, &families, options);
    let stats = |heldout: &[DVector<f64>]| {
        let (mut z2, mut m2, mut max, mut count) = (0.0, 0.0, 0.0f64, 0usize);
        for e in heldout {
            for i in 0..e.len() {
                z2 += e[i] * e[i];
                let m = e[i] * data.sigma[i];
                m2 += m * m;
                max = max.max(m.abs());
                count += 1;
            }
        }
        let c = count.max(1) as f64;
        ((z2 / c).sqrt(), (m2 / c).sqrt(), max)
    };
    let (z0, m0, max0) = stats(&s.heldout_before);
    let (z1, m1, max1) = stats(&s.heldout_after);
    Selection {
        chosen: s.chosen,
        steps: s.steps,
        heldout_rms_z_before: z0,
        heldout_rms_z_after: z1,
        heldout_rms_m_before: m0,
        heldout_rms_m_after: m1,
        heldout_max_m_before: max0,
        heldout_max_m_after: max1,
        chi2_per_dof_after: s.chi2_per_dof_after,
    }
}

struct Scored {
    family: usize,
    variant: usize,
    bic: f64,
    score: CandidateScore,
    /// The candidate's fitted effect over the (arranged) whitened rows, with what the declared
    /// parameters and the terms chosen so far explain of it taken out (an instrument's pose takes
    /// any constant, so two drifts that differ by one are the same here).
    effect: DVector<f64>,
}

/// Correlation of two effects that the base's columns have been projected out of: the cosine of
/// the angle between them (they share the base's span, so no mean is taken separately).
fn correlation(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    let (na, nb) = (a.norm(), b.norm());
    if a.len() != b.len() || !(na > 0.0 && nb > 0.0) {
        return 0.0;
    }
    a.dot(b) / (na * nb)
}

/// F test of the SSR a block of k columns explains, against the residual variance with it.
fn f_test(explained: f64, k: usize, ssr: f64, dof: f64) -> f64 {
    if k == 0 || !(explained > 0.0) || !(dof > 0.0) || !(ssr > 0.0) {
        return 1.0;
    }
    let f = (explained / k as f64) / (ssr / dof);
    FisherSnedecor::new(k as f64, dof)
        .map(|d| d.sf(f))
        .unwrap_or(1.0)
}

/// The joint distance from zero of the parameters `main` (indices into `values`; empty: all), in
/// σ: the normal score with the same tail probability as their Wald χ² (|v|/σ for one).
pub fn significance_sigma(values: &[f64], covariance: &DMatrix<f64>, main: &[usize]) -> f64 {
    let idx: Vec<usize> = if main.is_empty() {
        (0..values.len()).collect()
    } else {
        main.to_vec()
    };
    if idx.is_empty() {
        return 0.0;
    }
    let v = DVector::from_iterator(idx.len(), idx.iter().map(|&i| values[i]));
    let c = DMatrix::from_fn(idx.len(), idx.len(), |a, b| covariance[(idx[a], idx[b])]);
    let (inv, rank) = crate::blocked_least_squares::pseudo_inverse(&c);
    if rank == 0 {
        return 0.0;
    }
    let chi2 = (v.transpose() * inv * &v)[0].max(0.0);
    if rank == 1 {
        return chi2.sqrt();
    }
    use statrs::distribution::{ChiSquared, Normal};
    let p = ChiSquared::new(rank as f64)
        .map(|d| d.sf(chi2))
        .unwrap_or(1.0);
    if p <= 0.0 {
        return chi2.sqrt();
    }
    Normal::new(0.0, 1.0)
        .map(|n| n.inverse_cdf(1.0 - p / 2.0))
        .unwrap_or(0.0)
        .max(0.0)
}

/// BICs closer than this (in BIC units) are equal for ordering: round-off in the fits — a
/// different summation order, another build — must not decide between two candidates the data
/// cannot tell apart; such ties go to the label, so the same data always give the same pick.
const BIC_ROUND_OFF: f64 = 1e-6;

/// Candidates by BIC (equal within [`BIC_ROUND_OFF`]), then by family label and variant name.
fn by_bic_then_label(families: &[Family], a: &Scored, b: &Scored) -> std::cmp::Ordering {
    if (a.bic - b.bic).abs() > BIC_ROUND_OFF {
        return a.bic.total_cmp(&b.bic);
    }
    let name = |s: &Scored| {
        let f = &families[s.family];
        (f.label.clone(), f.variants[s.variant].name.clone())
    };
    name(a).cmp(&name(b))
}

fn bic(n: f64, ssr: f64, k: f64) -> f64 {
    n * (ssr.max(f64::MIN_POSITIVE) / n).ln() + k * n.ln()
}

/// Run the forward selection over candidate families on whitened data: forward steps, then
/// backward elimination, then swaps (each chosen term replaced by a candidate that explains the
/// data better given the others — a flexible term chosen early that stood in for two effects,
/// an instrument drifting along x and z where a warm-up and a structure's growth were, gives way
/// once one of them is in), then backward elimination again.
pub fn select_families(
    data: &WhitenedData,
    families: &[Family],
    options: &SelectionOptions,
) -> FamilySelection {
    let sel = Selector::new(data, families, options);
    let mut chosen: Vec<(usize, usize)> = Vec::new();
    let mut base = sel.base_of(&chosen);
    let before_fit = base.clone();
    let mut steps = Vec::new();
    while chosen.len() < options.max_terms {
        let step = sel.forward_step(&base, &chosen);
        let pick = step.chosen.map(|f| (f, step.chosen_variant));
        steps.push(step.step);
        match pick {
            Some(p) => {
                chosen.push(p);
                base = sel.base_of(&chosen);
            }
            None => break,
        }
    }
    let mut dropped = sel.backward(&mut chosen);
    let swapped = sel.swaps(&mut chosen);
    if !swapped.is_empty() {
        dropped.extend(sel.backward(&mut chosen));
    }
    base = sel.base_of(&chosen);
    sel.outcome(data, chosen, steps, dropped, swapped, &before_fit, &base)
}

/// What one forward step found: its record, and the variant of the family it chose.
struct ForwardStep {
    step: SelectionStep,
    chosen: Option<usize>,
    chosen_variant: usize,
}

/// The selection's data, arranged by blocks once, and the scoring of candidates against a base.
struct Selector<'a> {
    families: &'a [Family],
    options: &'a SelectionOptions,
    rows: BlockedRows,
    b: DVector<f64>,
    arranged: Vec<Vec<DMatrix<f64>>>,
    arranged_declared: DMatrix<f64>,
    n: f64,
    /// Variants tried in all (the Bonferroni factor).
    tried: usize,
}

impl<'a> Selector<'a> {
    fn new(data: &WhitenedData, families: &'a [Family], options: &'a SelectionOptions) -> Self {
        let n = data.b.len();
        let rows = BlockedRows::new(&data.folds, n);
        let b = rows.arrange_vector(&data.b);
        let arranged = families
            .iter()
            .map(|f| {
                f.variants
                    .iter()
                    .map(|v| rows.arrange(&v.columns))
                    .collect()
            })
            .collect();
        let arranged_declared = rows.arrange(&data.declared);
        let tried = families.iter().map(|f| f.variants.len()).sum();
        Self {
            families,
            options,
            rows,
            b,
            arranged,
            arranged_declared,
            n: n as f64,
            tried,
        }
    }

    /// The declared columns and the chosen variants' columns, fitted.
    fn base_of(&self, chosen: &[(usize, usize)]) -> BaseFit {
        let extra: Vec<&DMatrix<f64>> = chosen.iter().map(|&(f, v)| &self.arranged[f][v]).collect();
        let p = self.arranged_declared.ncols() + extra.iter().map(|c| c.ncols()).sum::<usize>();
        let mut all = DMatrix::zeros(self.b.len(), p);
        all.columns_mut(0, self.arranged_declared.ncols())
            .copy_from(&self.arranged_declared);
        let mut at = self.arranged_declared.ncols();
        for c in extra {
            all.columns_mut(at, c.ncols()).copy_from(c);
            at += c.ncols();
        }
        BaseFit::new(&self.rows, all, self.b.clone())
    }

    fn profiled_of(&self, chosen: &[(usize, usize)]) -> usize {
        chosen
            .iter()
            .map(|&(f, v)| self.families[f].variants[v].profiled)
            .sum()
    }

    fn bic_of(&self, base: &BaseFit, chosen: &[(usize, usize)]) -> f64 {
        bic(
            self.n,
            base.ssr(),
            (base.rank() + self.profiled_of(chosen)) as f64,
        )
    }

    /// The held-out error on the blocking schemes that judge a family.
    fn judged(by: &Option<Vec<usize>>, per_scheme: &[f64]) -> f64 {
        match by {
            None => per_scheme.iter().sum(),
            Some(list) => list.iter().filter_map(|&s| per_scheme.get(s)).sum(),
        }
    }

    /// Variant `vi` of family `fi` added to `base` (which holds `chosen`): its fit, tests and
    /// effect.
    fn score(&self, base: &BaseFit, chosen: &[(usize, usize)], fi: usize, vi: usize) -> Scored {
        let (fam, var) = (&self.families[fi], &self.families[fi].variants[vi]);
        let nf = self.n;
        let c: CandidateFit = base.candidate(&self.rows, &self.arranged[fi][vi]);
        let k = var.columns.ncols();
        let dof = nf - c.rank as f64;
        let sigma2 = if dof > 0.0 {
            c.ssr / dof
        } else {
            f64::INFINITY
        };
        let values: Vec<f64> = (0..k).map(|j| var.base_values[j] + c.values[j]).collect();
        let sigmas: Vec<f64> = (0..k)
            .map(|j| (c.unscaled_covariance[(j, j)].max(0.0) * sigma2).sqrt())
            .collect();
        let p = if c.separable {
            f_test(c.explained, k, c.ssr, dof)
        } else {
            1.0
        };
        let p_adjusted = (p * self.tried as f64 * var.search_multiplicity.max(1.0)).min(1.0);
        let plausible = values
            .iter()
            .zip(&var.ranges)
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi);
        let usual = values
            .iter()
            .zip(&var.usual)
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi);
        let significance = significance_sigma(
            &c.values.iter().copied().collect::<Vec<_>>(),
            &(&c.unscaled_covariance * sigma2),
            &var.main,
        );
        let bic_with = bic(
            nf,
            c.ssr,
            (c.rank + self.profiled_of(chosen) + var.profiled) as f64,
        ) + 2.0 * var.search_multiplicity.max(1.0).ln();
        let delta_bic = bic_with - self.bic_of(base, chosen);
        let (cv_with, cv_without) = (
            Self::judged(&fam.judged_by, &c.heldout_by_scheme),
            Self::judged(&fam.judged_by, &base.heldout_by_scheme()),
        );
        let heldout_gain = if cv_without > 0.0 {
            1.0 - cv_with / cv_without
        } else {
            0.0
        };
        let supported = c.separable
            && p_adjusted <= self.options.alpha
            && delta_bic < 0.0
            && heldout_gain >= self.options.min_cv_gain
            && significance >= MIN_SIGNIFICANCE_SIGMA;
        let accepted = supported && plausible;
        let score = CandidateScore {
            label: fam.label.clone(),
            variant: var.name.clone(),
            heldout_ssr: c.heldout_ssr,
            heldout_gain,
            wald_p_adjusted: p_adjusted,
            plausible,
            usual,
            significance_sigma: significance,
            supported,
            separable: c.separable,
            delta_bic,
            values,
            sigmas,
            accepted,
        };
        let effect = base.project_out(
            &(&self.arranged[fi][vi] * DVector::from_iterator(k, (0..k).map(|j| c.values[j]))),
        );
        Scored {
            family: fi,
            variant: vi,
            bic: bic_with,
            score,
            effect,
        }
    }

    /// Every family not chosen, by its representative variant: its acceptable variant of lowest
    /// BIC, else its supported (refused) one, else its lowest BIC.
    fn per_family(&self, base: &BaseFit, chosen: &[(usize, usize)]) -> Vec<Scored> {
        let mut out = Vec::new();
        for (fi, fam) in self.families.iter().enumerate() {
            if chosen.iter().any(|&(f, _)| f == fi) {
                continue;
            }
            let rank = |s: &CandidateScore| (s.accepted, s.supported);
            let best = (0..fam.variants.len())
                .map(|vi| self.score(base, chosen, fi, vi))
                .reduce(|b, s| {
                    if rank(&s.score) > rank(&b.score)
                        || (rank(&s.score) == rank(&b.score) && s.bic < b.bic - BIC_ROUND_OFF)
                    {
                        s
                    } else {
                        b
                    }
                });
            out.extend(best);
        }
        out
    }

    /// The acceptable family of lowest BIC among the physical (or the empirical) ones, ties —
    /// within [`TIE_BIC`], or confounded within [`CONFOUNDED_BIC`] — resolved by convention.
    fn best_of<'s>(&self, per_family: &'s [Scored], physical: bool) -> Option<&'s Scored> {
        let families = self.families;
        let accepted: Vec<&Scored> = per_family
            .iter()
            .filter(|s| s.score.accepted && families[s.family].physical == physical)
            .collect();
        let lowest = *accepted
            .iter()
            .min_by(|a, b| by_bic_then_label(families, a, b))?;
        let size = |s: &Scored| {
            families[s.family].variants[s.variant].columns.ncols()
                + families[s.family].variants[s.variant].profiled
        };
        let tied = |s: &Scored| {
            s.bic <= lowest.bic + TIE_BIC
                || (s.bic <= lowest.bic + CONFOUNDED_BIC
                    && correlation(&s.effect, &lowest.effect).abs() > CONFOUNDED_CORRELATION)
        };
        accepted.into_iter().filter(|s| tied(s)).min_by(|a, b| {
            preference(&families[a.family].term)
                .cmp(&preference(&families[b.family].term))
                .then(size(a).cmp(&size(b)))
                .then_with(|| by_bic_then_label(families, a, b))
        })
    }

    /// One forward step from `base` (holding `chosen`).
    fn forward_step(&self, base: &BaseFit, chosen: &[(usize, usize)]) -> ForwardStep {
        let per_family = self.per_family(base, chosen);
        let options = self.options;
        let pick = match (
            self.best_of(&per_family, true),
            self.best_of(&per_family, false),
        ) {
            (Some(p), Some(e)) => Some(
                if e.bic
                    < p.bic
                        - options
                            .empirical_margin
                            .max(options.empirical_margin_relative * p.score.delta_bic.abs())
                {
                    e
                } else {
                    p
                },
            ),
            (p, e) => p.or(e),
        };
        // a physical candidate the data support better than the pick, refused for impossible
        // values: nothing is named in its place (one whose effect the pick shares — correlated
        // beyond CONFOUNDED_CORRELATION — is the pick's effect at an impossible value: the pick,
        // possible, explains it as well)
        let refused = per_family
            .iter()
            .filter(|s| s.score.supported && !s.score.accepted && self.families[s.family].physical)
            .min_by(|a, b| by_bic_then_label(self.families, a, b))
            .filter(|r| {
                pick.is_none_or(|p| {
                    r.bic < p.bic - TIE_BIC
                        && correlation(&r.effect, &p.effect).abs() <= CONFOUNDED_CORRELATION
                })
            });
        let pick = if refused.is_some() { None } else { pick };
        let alternatives: Vec<StepAlternative> = match pick {
            None => Vec::new(),
            Some(p) => per_family
                .iter()
                .filter(|s| {
                    s.family != p.family
                        && s.score.accepted
                        && self.families[s.family].physical == self.families[p.family].physical
                })
                .filter_map(|s| {
                    let correlation = correlation(&s.effect, &p.effect);
                    let delta_bic = s.bic - p.bic;
                    (delta_bic < TIE_BIC || correlation.abs() > CONFOUNDED_CORRELATION).then_some(
                        StepAlternative {
                            family: s.family,
                            variant: s.variant,
                            delta_bic,
                            correlation,
                        },
                    )
                })
                .collect(),
        };
        let (chosen_family, chosen_variant) =
            (pick.map(|p| p.family), pick.map_or(0, |p| p.variant));
        let refused = refused.map(|r| r.family);
        let step = SelectionStep {
            heldout_ssr_before: base.heldout_ssr(),
            scores: per_family.into_iter().map(|s| s.score).collect(),
            chosen: chosen_family,
            refused,
            alternatives,
        };
        ForwardStep {
            step,
            chosen: chosen_family,
            chosen_variant,
        }
    }

    /// Backward elimination: each chosen term tested given all the others (F test, Bonferroni
    /// over the chosen, held-out gain); the least significant dropped while one fails. Returns
    /// the labels dropped.
    fn backward(&self, chosen: &mut Vec<(usize, usize)>) -> Vec<String> {
        let mut dropped = Vec::new();
        while !chosen.is_empty() {
            let mut worst: Option<(usize, f64)> = None;
            for i in 0..chosen.len() {
                let others: Vec<(usize, usize)> = chosen
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, c)| *c)
                    .collect();
                let without = self.base_of(&others);
                let (f, v) = chosen[i];
                let c = without.candidate(&self.rows, &self.arranged[f][v]);
                let dof = self.n - c.rank as f64;
                let p = if c.separable {
                    (f_test(c.explained, self.arranged[f][v].ncols(), c.ssr, dof)
                        * chosen.len() as f64)
                        .min(1.0)
                } else {
                    1.0
                };
                let by = &self.families[f].judged_by;
                let cv_ok = Self::judged(by, &c.heldout_by_scheme)
                    <= Self::judged(by, &without.heldout_by_scheme())
                        * (1.0 - self.options.min_cv_gain);
                let p = if cv_ok { p } else { 1.0 };
                if p > self.options.alpha && worst.is_none_or(|(_, wp)| p > wp) {
                    worst = Some((i, p));
                }
            }
            match worst {
                Some((i, _)) => dropped.push(self.families[chosen.remove(i).0].label.clone()),
                None => break,
            }
        }
        dropped
    }

    /// Swaps: each chosen term in turn is taken out, and the acceptable candidate (of the same
    /// kind: physical for physical) that lowers the BIC of the rest most — by more than
    /// [`TIE_BIC`] below the model with the term — replaces it; repeated while one does (at most
    /// twice per chosen term). Returns (replaced, replacement) labels.
    fn swaps(&self, chosen: &mut [(usize, usize)]) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for _round in 0..2 * chosen.len() {
            let current = self.bic_of(&self.base_of(chosen), chosen);
            let mut best: Option<(usize, Scored)> = None;
            for i in 0..chosen.len() {
                let others: Vec<(usize, usize)> = chosen
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, c)| *c)
                    .collect();
                let base = self.base_of(&others);
                let physical = self.families[chosen[i].0].physical;
                // a term at usual values gives way to one at unusual values only on decisive
                // evidence: a linear positioning error at a near-constant temperature is also a
                // scale expanding with that temperature's small drift, at an α no machine has
                let incumbent_usual = self
                    .score(&base, &others, chosen[i].0, chosen[i].1)
                    .score
                    .usual;
                for s in self.per_family(&base, chosen) {
                    let margin = if incumbent_usual && !s.score.usual {
                        DECISIVE_BIC
                    } else {
                        TIE_BIC
                    };
                    if !s.score.accepted
                        || self.families[s.family].physical != physical
                        || s.bic >= current - margin
                    {
                        continue;
                    }
                    if best.as_ref().is_none_or(|(_, b)| s.bic < b.bic) {
                        best = Some((i, s));
                    }
                }
            }
            let Some((i, s)) = best else { break };
            out.push((
                self.families[chosen[i].0].label.clone(),
                self.families[s.family].label.clone(),
            ));
            chosen[i] = (s.family, s.variant);
        }
        out
    }

    /// The selection's outcome: the chosen terms' parameters from the full-data fit of
    /// everything chosen, and the held-out figures before and after.
    #[allow(clippy::too_many_arguments)]
    fn outcome(
        &self,
        data: &WhitenedData,
        chosen: Vec<(usize, usize)>,
        steps: Vec<SelectionStep>,
        dropped: Vec<String>,
        swapped: Vec<(String, String)>,
        before_fit: &BaseFit,
        base: &BaseFit,
    ) -> FamilySelection {
        let x = base.solution();
        let dof = (self.n - base.rank() as f64).max(1.0);
        let sigma2 = base.ssr() / dof;
        let cov = base.unscaled_covariance();
        let mut col = data.declared.ncols();
        let mut chosen_terms = Vec::new();
        for &(f, v) in &chosen {
            let fam = &self.families[f];
            let var = &fam.variants[v];
            let k = var.columns.ncols();
            let parameters = (0..k)
                .map(|j| {
                    (
                        var.parameter_names[j].clone(),
                        var.base_values[j] + x[col + j],
                        (cov[(col + j, col + j)].max(0.0) * sigma2).sqrt(),
                        var.units[j].clone(),
                    )
                })
                .collect();
            chosen_terms.push(ChosenTerm {
                candidate: f,
                variant: v,
                label: fam.label.clone(),
                term: fam.term.clone(),
                physical: fam.physical,
                parameters,
            });
            col += k;
        }
        let restore = |v: Vec<DVector<f64>>| {
            v.iter()
                .map(|e| self.rows.restore_vector(e))
                .collect::<Vec<_>>()
        };
        FamilySelection {
            chosen: chosen_terms,
            steps,
            dropped,
            swapped,
            heldout_before: restore(before_fit.heldout_residuals(&self.rows)),
            heldout_after: restore(base.heldout_residuals(&self.rows)),
            residual_after: self.rows.restore_vector(&base.residuals()),
            chi2_per_dof_before: before_fit.ssr() / (self.n - before_fit.rank() as f64).max(1.0),
            chi2_per_dof_after: base.ssr() / dof,
            declared_increment: x.rows(0, data.declared.ncols()).into_owned(),
        }
    }
}
