//! Stage 7 of the diagnosis: the augmented model judged against the declared one.
//!
//! * Held-out figures before and after: the declared model refitted, and the augmented model
//!   with its empirical corrections, each refitted linearly per held-out block (blocks of time
//!   and of workspace; an empirical correction that one blocking cannot judge takes it out of
//!   both figures);
//! * the found parameters' σ: the final fit's independent-rows covariance, widened to the
//!   sandwich covariance of the scores in blocks of time (Newey–West) or clustered by place
//!   where the residuals are correlated, plus the shift a candidate the data support but the
//!   selection declined would cause (a bias no covariance shows);
//! * each added term's significance: the joint distance from zero of its main parameters in
//!   those σ — a term below [`crate::selection::MIN_SIGNIFICANCE_SIGMA`] is not a finding;
//! * each empirical correction's net effect on the recorded points: its values with what the
//!   model's free parameters take of it projected out (the size a user sees, never a
//!   coefficient).

use std::collections::BTreeMap;

use metrocell_estimation::RecordFrame;
use metrocell_model::ForwardModel;
use metrocell_physics::PhysicsError;
use nalgebra::{DMatrix, DVector, Vector3};

use crate::augmented_stage::Augmented;
use crate::blocked_least_squares::{pseudo_inverse, BaseFit, BlockedRows};
use crate::candidate_columns::ColumnContext;
use crate::candidate_stage::{empirical_columns, expand_folds, Prepared, Source};
use crate::declared_stage::DeclaredStage;
use crate::empirical::FittedEmpirical;
use crate::reference_columns::{nest_columns, with_columns};
use crate::report::{FitFigures, UncertaintyNote};
use crate::residual_view::ResidualView;
use crate::selection::{significance_sigma, Family, FamilySelection};

/// What the judgement found.
pub(crate) struct Judged {
    pub view1: ResidualView,
    pub before: FitFigures,
    pub after: FitFigures,
    /// Workpiece-frame residuals of the full-data fits, m.
    pub before_res: Vec<Vector3<f64>>,
    pub after_res: Vec<Vector3<f64>>,
    /// Held-out residual norms of the first judging scheme, m.
    pub held_before: Vec<f64>,
    pub held_after: Vec<f64>,
    /// The augmented model's parameter names, and each one's σ where fitted.
    pub names: Vec<String>,
    pub sigmas: Vec<Option<f64>>,
    /// Each empirical correction: its basis, coefficients, their σ, and its net effect on the
    /// records along its axis (m).
    pub empirical: Vec<FittedEmpirical>,
    /// The whitened residual of the full-data fit after everything.
    pub whitened_after: Vec<f64>,
    /// Each added term's (label, significance in σ of its main parameters).
    pub significance: Vec<(String, f64)>,
    pub uncertainty: UncertaintyNote,
    pub messages: Vec<String>,
    /// Parameters (`label.param`) the refit left on a bound of their possible range (set by the
    /// caller from the refit).
    pub at_bound: Vec<(String, String)>,
}

/// Inputs of the judgement that do not change when a term is dropped and the rest refitted.
pub(crate) struct JudgeInputs<'a> {
    pub machine: &'a metrocell_model::MachineGeometry,
    pub declared_model: &'a ForwardModel<'a>,
    pub stage: &'a DeclaredStage,
    pub x0: &'a [f64],
    pub free0: &'a [usize],
    pub view0: &'a ResidualView,
    pub folds_time: &'a [usize],
    pub folds_space: &'a [usize],
    pub selection: &'a FamilySelection,
    pub families: &'a [Family],
    pub prepared: &'a [Prepared],
    pub alpha: f64,
}

/// Judge the augmented model at the refit `x1`.
pub(crate) fn judge(
    inp: &JudgeInputs,
    aug: &Augmented,
    x1: &[f64],
) -> Result<Judged, PhysicsError> {
    let set = &inp.stage.set;
    let n = set.records.len();
    let model_aug = aug.model(inp.machine)?;
    let names = model_aug.param_names();
    let view1 = ResidualView::new(&model_aug, x1, &set.records, &set.frame)?;
    // the free columns of the augmented model (an instrument pose only where the records are in
    // an instrument frame) and the empirical corrections' columns
    let free1: Vec<usize> = aug
        .setup
        .free
        .iter()
        .enumerate()
        .filter(|(k, f)| {
            **f && !(set.frame == RecordFrame::Machine
                && metrocell_estimation::check_points::is_placement_parameter(&names[*k]))
        })
        .map(|(k, _)| k)
        .collect();
    let mut ctx_all = ColumnContext::new(&model_aug, x1, &set.records, &view1.whitening)?;
    // the free parameters and each reference nest's position (a nuisance; after them in the
    // columns, before the empirical corrections)
    let nests = nest_columns(&set.records, &view1);
    let free_cols = with_columns(ctx_all.declared_columns(&free1)?, &nests);
    let emp_cols: Vec<DMatrix<f64>> = aug
        .empirical
        .iter()
        .map(|e| empirical_columns(&view1, &e.basis))
        .collect();
    let a1 = hstack(&free_cols, &emp_cols);
    let row_folds = vec![expand_folds(inp.folds_time), expand_folds(inp.folds_space)];
    let rows = BlockedRows::new(&row_folds, 3 * n);
    let after_fit = BaseFit::new(
        &rows,
        rows.arrange(&a1),
        rows.arrange_vector(&view1.whitened()),
    );
    let before_cols = with_columns(
        ColumnContext::new(
            inp.declared_model,
            inp.x0,
            &set.records,
            &inp.view0.whitening,
        )?
        .declared_columns(inp.free0)?,
        &nest_columns(&set.records, inp.view0),
    );
    let before_fit = BaseFit::new(
        &rows,
        rows.arrange(&before_cols),
        rows.arrange_vector(&inp.view0.whitened()),
    );
    let mut messages = Vec::new();
    let schemes = judging_schemes(inp, aug, &mut messages);
    let (before, before_res, held_before) = figures(&before_fit, inp.view0, &rows, &schemes);
    let (after, after_res, held_after) = figures(&after_fit, &view1, &rows, &schemes);
    // σ² of each column: independent rows, widened where the residuals are correlated in time
    // or at one place, plus the shift of a supported-but-declined candidate
    let cov = after_fit.unscaled_covariance().clone();
    let dof1 = (after_fit.rows() as f64 - after_fit.rank() as f64).max(1.0);
    let sigma2 = after_fit.ssr() / dof1;
    let e1 = rows.restore_vector(&after_fit.residuals());
    let serial = crate::serial_correlation::sandwich(&a1, &e1, &cov, &view1.time, after_fit.rank());
    let place =
        crate::serial_correlation::by_place(&a1, &e1, &cov, &view1.position, after_fit.rank());
    let (shift2, alternatives) = declined_shifts(inp, aug, &mut ctx_all, &view1, &a1, &e1, &cov);
    let variance = |j: usize| -> f64 {
        let classical = cov[(j, j)].max(0.0) * sigma2;
        let in_time = serial.as_ref().map_or(0.0, |s| s.covariance[(j, j)]);
        let in_place = place.as_ref().map_or(0.0, |s| s[(j, j)]);
        classical.max(in_time).max(in_place) + shift2[j]
    };
    let sol = after_fit.solution().clone();
    let empirical = empirical_fitted(
        aug,
        &view1,
        &free_cols,
        &emp_cols,
        &sol,
        free1.len() + nests.ncols(),
        &variance,
    );
    let mut sigmas = vec![None; names.len()];
    for (j, &k) in free1.iter().enumerate() {
        sigmas[k] = Some(variance(j).sqrt());
    }
    // the significance of each added term's main parameters, in the widened σ (the classical
    // correlations, the widened diagonal)
    let significance = aug
        .added
        .iter()
        .map(|a| {
            let idx: Vec<usize> = a
                .main
                .iter()
                .filter_map(|p| {
                    free1
                        .iter()
                        .position(|&k| names[k] == format!("{}.{p}", a.label))
                })
                .collect();
            let values: Vec<f64> = idx.iter().map(|&j| x1[free1[j]]).collect();
            // the classical correlations with the widened variances on the diagonal
            let c = DMatrix::from_fn(idx.len(), idx.len(), |r, s| {
                let (i, j) = (idx[r], idx[s]);
                let correlation =
                    cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).max(f64::MIN_POSITIVE).sqrt();
                correlation * (variance(i) * variance(j)).sqrt()
            });
            (a.label.clone(), significance_sigma(&values, &c, &[]))
        })
        .collect();
    let uncertainty = uncertainty_note(
        aug,
        &names,
        &free1,
        &cov,
        sigma2,
        &variance,
        &serial,
        place.is_some(),
        &alternatives,
    );
    let whitened_after: Vec<f64> = e1.iter().copied().collect();
    Ok(Judged {
        view1,
        before,
        after,
        before_res,
        after_res,
        held_before,
        held_after,
        names,
        sigmas,
        empirical,
        whitened_after,
        significance,
        uncertainty,
        messages,
        at_bound: Vec::new(),
    })
}

fn hstack(first: &DMatrix<f64>, rest: &[DMatrix<f64>]) -> DMatrix<f64> {
    let cols = first.ncols() + rest.iter().map(|c| c.ncols()).sum::<usize>();
    let mut out = DMatrix::zeros(first.nrows(), cols);
    out.columns_mut(0, first.ncols()).copy_from(first);
    let mut at = first.ncols();
    for c in rest {
        out.columns_mut(at, c.ncols()).copy_from(c);
        at += c.ncols();
    }
    out
}

/// The blockings every chosen term can be judged on (an empirical correction in time cannot
/// predict a held-out block of time).
fn judging_schemes(inp: &JudgeInputs, aug: &Augmented, messages: &mut Vec<String>) -> Vec<usize> {
    let mut schemes: Vec<usize> = vec![0, 1];
    let chosen: Vec<usize> = aug
        .added
        .iter()
        .map(|a| a.candidate)
        .chain(aug.freed.iter().map(|f| f.candidate))
        .chain(aug.empirical.iter().map(|e| e.candidate))
        .collect();
    for c in chosen {
        if let Some(by) = &inp.families[c].judged_by {
            schemes.retain(|s| by.contains(s));
        }
    }
    if schemes.is_empty() {
        messages.push("the empirical corrections in time and over the workspace cannot both be judged on held-out blocks; the held-out figures use both blockings".into());
        schemes = vec![0, 1];
    }
    schemes
}

/// Held-out and full-data figures of a linear fit over the blocks, with the workpiece-frame
/// residuals of the full-data fit and the held-out residual norm of each record (first scheme).
fn figures(
    fitb: &BaseFit,
    view: &ResidualView,
    rows: &BlockedRows,
    schemes: &[usize],
) -> (FitFigures, Vec<Vector3<f64>>, Vec<f64>) {
    let held = fitb.heldout_residuals(rows);
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
    let names = schemes
        .iter()
        .map(|&s| {
            if s == 0 {
                "time".to_string()
            } else {
                "workspace".to_string()
            }
        })
        .collect();
    (
        FitFigures {
            heldout_rms_m: (ss / count.max(1) as f64).sqrt(),
            heldout_max_m: max,
            chi2_per_dof: fitb.ssr() / dof,
            rms_m: rms,
            heldout_blocks: names,
        },
        full,
        first,
    )
}

/// The choice of model: a candidate the data support (significant after correction, lower BIC)
/// that the last step declined only for its small held-out gain may still belong, and whatever
/// the found terms absorb of it is a bias no covariance shows. Each such candidate's shift of
/// the parameters (were it added to the final fit) counts in their σ (the largest shift per
/// parameter, in quadrature). Returns the squared shifts per column and each candidate's
/// description with its shift vector.
#[allow(clippy::too_many_arguments)]
fn declined_shifts(
    inp: &JudgeInputs,
    _aug: &Augmented,
    ctx_all: &mut ColumnContext,
    view1: &ResidualView,
    a1: &DMatrix<f64>,
    e1: &DVector<f64>,
    cov: &DMatrix<f64>,
) -> (Vec<f64>, Vec<(String, DVector<f64>)>) {
    let mut shift2 = vec![0.0f64; a1.ncols()];
    let mut alternatives = Vec::new();
    let Some(last) = inp.selection.steps.last().filter(|s| s.chosen.is_none()) else {
        return (shift2, alternatives);
    };
    for sc in last.scores.iter().filter(|c| {
        !c.accepted
            && c.separable
            && c.plausible
            && c.wald_p_adjusted <= inp.alpha
            && c.delta_bic < 0.0
    }) {
        let Some(f) = inp.families.iter().position(|f| f.label == sc.label) else {
            continue;
        };
        let Some(vi) = inp.families[f]
            .variants
            .iter()
            .position(|v| v.name == sc.variant)
        else {
            continue;
        };
        let columns = match &inp.prepared[f].source {
            Source::Term { family, kept } => {
                match ctx_all.columns(&family.variants[vi].config, family.placement) {
                    Ok(c) => c.columns.select_columns(&kept[vi]),
                    Err(_) => continue,
                }
            }
            Source::Empirical(bases) => empirical_columns(view1, &bases[vi]),
            Source::Freed { .. } => continue,
        };
        let Some(d) = crate::serial_correlation::shift_if_added(a1, e1, cov, &columns) else {
            continue;
        };
        for (j, v) in d.iter().enumerate() {
            shift2[j] = shift2[j].max(v * v);
        }
        let name = if sc.variant.is_empty() {
            sc.label.clone()
        } else {
            format!("{} ({})", sc.label, sc.variant)
        };
        alternatives.push((
            format!(
                "{name}: p = {:.1e} after correction, ΔBIC {:.0}, held-out gain {:.3}",
                sc.wald_p_adjusted, sc.delta_bic, sc.heldout_gain
            ),
            d,
        ));
    }
    (shift2, alternatives)
}

/// The empirical corrections' coefficients and σ from the joint fit, and each one's net effect
/// on the records: its values with what the free parameters take of it projected out, along its
/// workpiece axis (m).
fn empirical_fitted(
    aug: &Augmented,
    view1: &ResidualView,
    free_cols: &DMatrix<f64>,
    emp_cols: &[DMatrix<f64>],
    sol: &DVector<f64>,
    start: usize,
    variance: &dyn Fn(usize) -> f64,
) -> Vec<FittedEmpirical> {
    let (pinv, _) = pseudo_inverse(&free_cols.tr_mul(free_cols));
    let mut at = start;
    let mut out = Vec::new();
    for (k, e) in aug.empirical.iter().enumerate() {
        let len = emp_cols[k].ncols();
        // the judged residuals are the records' own (the refit took the corrections off, the
        // view does not): the joint fit's coefficients are the whole correction, not an
        // increment on the selection's (adding those counted the structure twice)
        let coefficients: Vec<f64> = (0..len).map(|j| sol[at + j]).collect();
        let sigmas: Vec<f64> = (0..len).map(|j| variance(at + j).sqrt()).collect();
        let whitened = &emp_cols[k] * DVector::from_column_slice(&coefficients);
        let net = &whitened - free_cols * (&pinv * free_cols.tr_mul(&whitened));
        let along: Vec<f64> = view1
            .to_workpiece_metres(&net)
            .iter()
            .map(|v| v[e.basis.axis])
            .collect();
        out.push((e.basis.clone(), coefficients, sigmas, along));
        at += len;
    }
    out
}

/// How the σ were made, in words, with each found parameter's widening factor.
#[allow(clippy::too_many_arguments)]
fn uncertainty_note(
    aug: &Augmented,
    names: &[String],
    free1: &[usize],
    cov: &DMatrix<f64>,
    sigma2: f64,
    variance: &dyn Fn(usize) -> f64,
    serial: &Option<crate::serial_correlation::SerialCovariance>,
    place: bool,
    alternatives: &[(String, DVector<f64>)],
) -> UncertaintyNote {
    let mut note = UncertaintyNote {
        blocks: serial.as_ref().map_or(0, |s| s.blocks),
        lag_blocks: serial.as_ref().map_or(0, |s| s.lag_blocks),
        place_clusters: place,
        ..Default::default()
    };
    let found: Vec<String> = aug
        .added
        .iter()
        .map(|a| format!("{}.", a.label))
        .chain(aug.freed.iter().map(|f| format!("{}.", f.label)))
        .collect();
    let is_found = |k: usize| found.iter().any(|l| names[k].starts_with(l.as_str()));
    let mut widened = BTreeMap::new();
    for (j, &k) in free1.iter().enumerate() {
        let classical = cov[(j, j)].max(0.0) * sigma2;
        if classical > 0.0 && variance(j) > classical && is_found(k) {
            widened.insert(names[k].clone(), (variance(j) / classical).sqrt());
        }
    }
    note.widened = widened;
    let how = match (serial, place) {
        (None, false) => "with independent rows (too few records to measure their correlation)".to_string(),
        (Some(s), _) => format!(
            "widened where the residuals are correlated in time (scores summed over {} blocks of time, Newey–West over {} neighbouring blocks){}",
            s.blocks,
            s.lag_blocks,
            if place { format!(" or at one place (scores clustered on a {0}×{0}×{0} grid over the workspace)", crate::serial_correlation::PLACE_CELLS) } else { String::new() }
        ),
        (None, true) => format!("widened where the residuals are correlated at one place (scores clustered on a {0}×{0}×{0} grid over the workspace)", crate::serial_correlation::PLACE_CELLS),
    };
    for (what, d) in alternatives {
        let moved: Vec<String> = free1
            .iter()
            .enumerate()
            .filter(|(j, &k)| is_found(k) && d[*j] * d[*j] > 0.1 * cov[(*j, *j)].max(0.0) * sigma2)
            .map(|(j, &k)| format!("{} by {:+.3e}", names[k], d[j]))
            .collect();
        if !moved.is_empty() {
            note.alternatives.push(format!("{what} — the data support it but the held-out test declined it; with it {}: counted in the σ", moved.join(", ")));
        }
    }
    let most = note.widened.iter().max_by(|a, b| a.1.total_cmp(b.1));
    note.statement = format!(
        "σ from the final fit's covariance, {how}{}",
        match most {
            Some((name, f)) => format!("; the correlation and the candidates the data support but the selection declined widen {} found parameters' σ, most {name} by {f:.2}×", note.widened.len()),
            None => "; nothing widens a found parameter's σ".into(),
        }
    );
    note
}
