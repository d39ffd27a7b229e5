//! Stage 4 of the diagnosis: what the selection runs on and what it chooses among.
//!
//! * [`SelectionFrame`]: the records the selection uses (a long recording thinned in time order),
//!   their held-out folds (blocks of time, blocks of workspace), the whitened residual of the
//!   declared fit and the declared free parameters' columns;
//! * [`candidates`]: every catalog term the declared model lacks that the records can inform
//!   (variants with their columns from the shared model, parameters the declared ones already
//!   explain set aside), a declared term held fixed that the data may contradict (freed), and
//!   the empirical corrections that never get a physical name.

use metrocell_estimation::{is_reference, MeasurementRecord, RecordFrame};
use metrocell_model::ForwardModel;
use metrocell_physics::{PhysicsError, TermId};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::blocked_least_squares::{pseudo_inverse, separable_columns};
use crate::candidate_columns::ColumnContext;
use crate::candidates::{candidate_families, Declared, NotTried, TermFamily};
use crate::declared_stage::DeclaredStage;
use crate::empirical::{bump_variants, time_variants, EmpiricalBasis};
use crate::folds::{time_blocks, within_groups, workspace_blocks};
use crate::periodogram::{independent_frequencies, strongest_period};
use crate::pipeline::{DeclaredModel, DiagnoseOptions};
use crate::reference_columns::{nest_columns, with_columns};
use crate::residual_view::ResidualView;
use crate::selection::{Family, Variant};
use crate::signal_inventory::SignalInventory;

/// A candidate variant ready for the selection, with what it came from.
pub(crate) struct Prepared {
    pub family: Family,
    pub source: Source,
}

pub(crate) enum Source {
    /// A catalog term; `kept[v]` are the indices (term parameter order) of variant v's
    /// parameters the data can separate from the declared ones.
    Term {
        family: TermFamily,
        kept: Vec<Vec<usize>>,
    },
    /// Declared parameters the model holds fixed, freed (`label.param` names).
    Freed {
        id: TermId,
        label: String,
        names: Vec<String>,
    },
    Empirical(Vec<EmpiricalBasis>),
}

/// What the selection runs on.
pub(crate) struct SelectionFrame {
    /// Fold of every used record: blocks of time, blocks of workspace.
    pub folds_time: Vec<usize>,
    pub folds_space: Vec<usize>,
    /// The records the selection uses (every record, or a thinning in time order).
    pub records: Vec<MeasurementRecord>,
    pub view: ResidualView,
    /// Whitened residual rows (3 per selection record) and the declared free columns.
    pub b: DVector<f64>,
    pub declared_cols: DMatrix<f64>,
    /// Per-row folds of the selection records (time, workspace).
    pub folds: Vec<Vec<usize>>,
}

/// Per-record folds expanded to the 3 rows of each record.
pub(crate) fn expand_folds(per_record: &[usize]) -> Vec<usize> {
    per_record.iter().flat_map(|&f| [f, f, f]).collect()
}

impl SelectionFrame {
    pub fn new(
        model: &ForwardModel,
        x0: &[f64],
        free0: &[usize],
        stage: &DeclaredStage,
        view0: &ResidualView,
        options: &DiagnoseOptions,
    ) -> Result<Self, PhysicsError> {
        let n = stage.set.records.len();
        // with one pose per placement of the instrument, blocks are cut within each placement
        let placements: Vec<Option<&str>> = stage
            .set
            .records
            .iter()
            .map(|r| r.signals.setup.as_deref())
            .collect();
        let folds_time = within_groups(&placements, |m| {
            time_blocks(
                &m.iter().map(|&i| view0.time[i]).collect::<Vec<_>>(),
                options.time_blocks,
            )
        });
        let folds_space = within_groups(&placements, |m| {
            workspace_blocks(
                &m.iter().map(|&i| view0.position[i]).collect::<Vec<_>>(),
                options.workspace_blocks,
            )
        });
        let stride = n.div_ceil(options.max_selection_records.max(1));
        let mut by_time: Vec<usize> = (0..n).collect();
        by_time.sort_by(|&a, &b| view0.time[a].total_cmp(&view0.time[b]));
        let idx: Vec<usize> = by_time.iter().step_by(stride).copied().collect();
        let records: Vec<MeasurementRecord> =
            idx.iter().map(|&i| stage.set.records[i].clone()).collect();
        let view = ResidualView::new(model, x0, &records, &stage.set.frame)?;
        // the declared free parameters, and each reference nest's position (a nuisance)
        let declared_cols = with_columns(
            ColumnContext::new(model, x0, &records, &view.whitening)?.declared_columns(free0)?,
            &nest_columns(&records, &view),
        );
        let b = view.whitened();
        let folds = vec![
            expand_folds(&idx.iter().map(|&i| folds_time[i]).collect::<Vec<_>>()),
            expand_folds(&idx.iter().map(|&i| folds_space[i]).collect::<Vec<_>>()),
        ];
        Ok(Self {
            folds_time,
            folds_space,
            records,
            view,
            b,
            declared_cols,
            folds,
        })
    }

    /// Weight 1/σ² of each selection record along workpiece axis `k`.
    fn weights(&self, k: usize) -> Vec<f64> {
        self.records
            .iter()
            .enumerate()
            .map(|(i, r)| {
                1.0 / (self.view.rotation(i) * r.covariance * self.view.rotation(i).transpose())
                    [(k, k)]
            })
            .collect()
    }

    /// The residual of each selection record along workpiece axis `k`.
    fn residual_along(&self, k: usize) -> Vec<f64> {
        (0..self.view.len())
            .map(|i| self.view.workpiece(i)[k])
            .collect()
    }
}

/// Empirical columns (whitened, records frame) of a basis for the records of `view`.
pub(crate) fn empirical_columns(view: &ResidualView, basis: &EmpiricalBasis) -> DMatrix<f64> {
    let k = basis.len();
    let mut out = DMatrix::zeros(3 * view.len(), k);
    let mut axis = Vector3::zeros();
    axis[basis.axis] = 1.0;
    for i in 0..view.len() {
        let w = view.whitening[i] * (view.rotation(i).transpose() * axis);
        for (j, v) in basis
            .values(view.time[i], &view.position[i])
            .iter()
            .enumerate()
        {
            out.fixed_view_mut::<3, 1>(3 * i, j).copy_from(&(w * *v));
        }
    }
    out
}

/// A parameter that does not carry a term's effect: the tracker warm-up's constant range offset
/// A (a fixed property of the instrument, tried beside the drift B).
pub(crate) fn is_nuisance(id: TermId, param: &str) -> bool {
    matches!((id, param), (TermId::TrackerWarmup, "offset"))
}

/// The lead of the strongest periodic structure in the residuals along each axis (with the
/// number of independent periods compared), for the cyclic screw error.
fn periodogram_leads(
    declared: &DeclaredModel,
    frame: &SelectionFrame,
    inventory: &SignalInventory,
) -> [Option<(f64, f64)>; 3] {
    let mut leads = [None; 3];
    for (k, lead) in leads.iter_mut().enumerate() {
        if !inventory.positions[k] {
            continue;
        }
        // the machine's points only: a reference nest has no axis position
        let machine: Vec<usize> = (0..frame.records.len())
            .filter(|&i| !is_reference(&frame.records[i]))
            .collect();
        let q: Vec<f64> = machine
            .iter()
            .map(|&i| frame.records[i].signals.axis_position[k].unwrap_or(0.0))
            .collect();
        let (res, w) = (frame.residual_along(k), frame.weights(k));
        let res: Vec<f64> = machine.iter().map(|&i| res[i]).collect();
        let w: Vec<f64> = machine.iter().map(|&i| w[i]).collect();
        let span = declared.machine.travel[k][1] - declared.machine.travel[k][0];
        if span.is_finite() && !q.is_empty() {
            let covered = q.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - q.iter().cloned().fold(f64::INFINITY, f64::min);
            *lead = strongest_period(&q, &res, &w, 1.5e-3, span / 3.0)
                .map(|p| (p.0, independent_frequencies(covered, 1.5e-3, span / 3.0)));
        }
    }
    leads
}

/// Every candidate the selection chooses among, and the catalog terms not tried with why.
pub(crate) fn candidates(
    declared: &DeclaredModel,
    model: &ForwardModel,
    stage: &DeclaredStage,
    x0: &[f64],
    frame: &SelectionFrame,
    options: &DiagnoseOptions,
) -> Result<(Vec<Prepared>, Vec<NotTried>), PhysicsError> {
    // what the machine's points can inform (a reference nest carries no axis positions)
    let machine_records: Vec<MeasurementRecord> = frame
        .records
        .iter()
        .filter(|r| !is_reference(r))
        .cloned()
        .collect();
    let mut inventory = SignalInventory::of(&machine_records);
    if let metrocell_model::MachineKinematics::SerialArm(arm) = &declared.machine.kinematics {
        inventory.gravity_torque_rms =
            crate::signal_inventory::gravity_torque_rms(arm, &machine_records);
    }
    let leads = periodogram_leads(declared, frame, &inventory);
    let decl = Declared {
        machine: declared.machine,
        machine_terms: declared.machine_terms,
        instrument_terms: &stage.instruments,
    };
    let (term_families, mut not_tried) = candidate_families(
        &decl,
        &inventory,
        &leads,
        stage.set.frame == RecordFrame::Machine,
    );
    let (declared_pinv, _) = pseudo_inverse(&frame.declared_cols.tr_mul(&frame.declared_cols));
    let mut ctx = ColumnContext::new(model, x0, &frame.records, &frame.view.whitening)?;
    let mut prepared = Vec::new();
    for tf in term_families {
        match term_candidate(&mut ctx, &tf, &declared_pinv, &frame.declared_cols) {
            Ok(p) => prepared.push(p),
            Err(reason) => not_tried.push(NotTried {
                term: tf.label.clone(),
                reason,
            }),
        }
    }
    prepared.extend(freed_candidates(
        &stage.instruments,
        model,
        stage,
        x0,
        &mut ctx,
        &declared_pinv,
        &frame.declared_cols,
        &mut not_tried,
    )?);
    if options.empirical {
        prepared.extend(empirical_candidates(frame, &declared_pinv));
    }
    Ok((prepared, not_tried))
}

/// A catalog term's variants with their separable columns, or why it cannot be tried.
fn term_candidate(
    ctx: &mut ColumnContext,
    tf: &TermFamily,
    declared_pinv: &DMatrix<f64>,
    declared_cols: &DMatrix<f64>,
) -> Result<Prepared, String> {
    let mut variants = Vec::new();
    let mut kept_all = Vec::new();
    let mut kept_configs = Vec::new();
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
        let kept_local = separable_columns(declared_pinv, declared_cols, &sub);
        if kept_local.is_empty() {
            continue;
        }
        let kept: Vec<usize> = kept_local.iter().map(|&j| linear[j]).collect();
        variants.push(Variant {
            name: v.name.clone(),
            columns: cols.columns.select_columns(&kept),
            parameter_names: kept.iter().map(|&j| specs[j].name.clone()).collect(),
            units: kept.iter().map(|&j| specs[j].unit.to_string()).collect(),
            ranges: kept
                .iter()
                .map(|&j| (specs[j].possible.lo, specs[j].possible.hi))
                .collect(),
            usual: kept
                .iter()
                .map(|&j| (specs[j].usual.lo, specs[j].usual.hi))
                .collect(),
            main: kept
                .iter()
                .enumerate()
                .filter(|(_, &j)| !is_nuisance(tf.id, &specs[j].name))
                .map(|(i, _)| i)
                .collect(),
            base_values: kept.iter().map(|&j| cols.term.params[j]).collect(),
            profiled: v.profiled,
            search_multiplicity: v.search_multiplicity,
        });
        kept_all.push(kept);
        kept_configs.push(v.clone());
    }
    if variants.is_empty() {
        return Err(last_error.unwrap_or_else(|| "these records cannot separate it from the declared parameters (its effect is the same as theirs here)".into()));
    }
    let family = TermFamily {
        variants: kept_configs,
        ..tf.clone()
    };
    Ok(Prepared {
        family: Family {
            label: tf.label.clone(),
            term: tf.id.as_str().into(),
            physical: true,
            variants,
            judged_by: None,
        },
        source: Source::Term {
            family,
            kept: kept_all,
        },
    })
}

/// A term the model declares but holds fixed at values the data may contradict: the air on the
/// beam (a model with a weather station declares refraction with no offset).
#[allow(clippy::too_many_arguments)]
fn freed_candidates(
    instruments: &metrocell_physics::model::TermModel,
    model: &ForwardModel,
    stage: &DeclaredStage,
    x0: &[f64],
    ctx: &mut ColumnContext,
    declared_pinv: &DMatrix<f64>,
    declared_cols: &DMatrix<f64>,
    not_tried: &mut Vec<NotTried>,
) -> Result<Vec<Prepared>, PhysicsError> {
    let names = model.param_names();
    let mut out = Vec::new();
    for t in instruments
        .terms
        .iter()
        .filter(|t| t.term.id() == TermId::Refraction)
    {
        let label = t.term.label();
        let name = format!("{label}.path_temperature_offset");
        let Some(k) = names.iter().position(|n| *n == name) else {
            continue;
        };
        if stage.setup.free[k] {
            continue;
        }
        let cols = ctx.declared_columns(&[k])?;
        if separable_columns(declared_pinv, declared_cols, &cols).is_empty() {
            not_tried.push(NotTried {
                term: label.clone(),
                reason:
                    "these records cannot separate the air's offset from the declared parameters"
                        .into(),
            });
            continue;
        }
        let spec = &t.term.params()[0];
        let variant = Variant {
            name: "freed".into(),
            columns: cols,
            parameter_names: vec![spec.name.clone()],
            units: vec![spec.unit.into()],
            ranges: vec![(spec.possible.lo, spec.possible.hi)],
            usual: vec![(spec.usual.lo, spec.usual.hi)],
            main: Vec::new(),
            base_values: vec![x0[k]],
            profiled: 0,
            search_multiplicity: 1.0,
        };
        out.push(Prepared {
            family: Family {
                label: label.clone(),
                term: TermId::Refraction.as_str().into(),
                physical: true,
                variants: vec![variant],
                judged_by: None,
            },
            source: Source::Freed {
                id: TermId::Refraction,
                label,
                names: vec![name],
            },
        });
    }
    Ok(out)
}

/// Empirical corrections per workpiece axis: a spline in time (judged on blocks of workspace)
/// and a local bump (judged on blocks of time), each shape only with the basis functions the
/// declared parameters do not already span.
fn empirical_candidates(frame: &SelectionFrame, declared_pinv: &DMatrix<f64>) -> Vec<Prepared> {
    let mut out = Vec::new();
    for axis in 0..3 {
        let res = frame.residual_along(axis);
        let w = frame.weights(axis);
        // scheme 0 = blocks of time, 1 = blocks of workspace: each empirical shape is judged on
        // the scheme it can predict
        for (all_bases, judged_by) in [
            (time_variants(&frame.view.time, axis), 1usize),
            (bump_variants(&frame.view.position, &res, &w, axis), 0usize),
        ] {
            let mut bases = Vec::new();
            let mut variants = Vec::new();
            for mut b in all_bases {
                let cols = empirical_columns(&frame.view, &b);
                let kept = separable_columns(declared_pinv, &frame.declared_cols, &cols);
                if kept.is_empty() {
                    continue;
                }
                let columns = cols.select_columns(&kept);
                if kept.len() < cols.ncols() {
                    b.kept = Some(kept);
                }
                let k = b.len();
                variants.push(Variant {
                    name: b.variant_name(),
                    columns,
                    parameter_names: (0..k).map(|j| format!("c{j}")).collect(),
                    units: vec!["m".into(); k],
                    ranges: vec![(-1.0, 1.0); k],
                    usual: vec![(-1.0, 1.0); k],
                    main: Vec::new(),
                    base_values: vec![0.0; k],
                    profiled: b.searched(),
                    search_multiplicity: b.search_multiplicity(),
                });
                bases.push(b);
            }
            if bases.is_empty() {
                continue;
            }
            out.push(Prepared {
                family: Family {
                    label: bases[0].label(),
                    term: "empirical".into(),
                    physical: false,
                    variants,
                    judged_by: Some(vec![judged_by]),
                },
                source: Source::Empirical(bases),
            });
        }
    }
    out
}
