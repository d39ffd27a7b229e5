//! Stage 6 of the diagnosis: the declared model with what the selection chose added to it, and
//! its nonlinear refit with the shared solver (lags, warm-up τ and leads refined), the empirical
//! corrections taken off the measurements meanwhile.

use metrocell_estimation::{estimate_nests, fit, is_reference, RecordSet};
use metrocell_model::{ForwardModel, MachineGeometry, ParameterSetup};
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, ConfigValue, PhysicsError, TermConfig, TermId};
use nalgebra::Vector3;

use crate::candidate_stage::{Prepared, Source};
use crate::candidates::Placement;
use crate::declared_stage::setup_by_name;
use crate::empirical::EmpiricalBasis;
use crate::pipeline::DiagnoseOptions;
use crate::residual_view::ResidualView;
use crate::selection::ChosenTerm;

/// A catalog term added to the model.
#[derive(Debug, Clone)]
pub(crate) struct AddedSource {
    /// Index of its family among the prepared candidates.
    pub candidate: usize,
    pub config: TermConfig,
    pub placement: Placement,
    /// Its parameters fitted by the refit (term parameter names).
    pub free: Vec<String>,
    /// Its parameters that carry its effect (for the significance test): the linear ones the
    /// data could separate, without nuisances.
    pub main: Vec<String>,
    pub variant: String,
    pub label: String,
    pub id: TermId,
}

/// A declared parameter set freed.
#[derive(Debug, Clone)]
pub(crate) struct FreedSource {
    pub candidate: usize,
    pub id: TermId,
    pub label: String,
    /// (`label.param`, selection value).
    pub values: Vec<(String, f64)>,
}

/// An empirical correction chosen: its family, its basis and its selection coefficients.
#[derive(Debug, Clone)]
pub(crate) struct EmpiricalChosen {
    pub candidate: usize,
    pub basis: EmpiricalBasis,
    pub coefficients: Vec<f64>,
}

/// The augmented model (owned terms; [`Augmented::model`] builds the forward model over them).
pub(crate) struct Augmented {
    pub machine_terms: TermModel,
    pub instruments: TermModel,
    pub setup: ParameterSetup,
    pub added: Vec<AddedSource>,
    pub freed: Vec<FreedSource>,
    pub empirical: Vec<EmpiricalChosen>,
}

impl Augmented {
    pub fn model<'a>(
        &'a self,
        machine: &'a MachineGeometry,
    ) -> Result<ForwardModel<'a>, PhysicsError> {
        ForwardModel::new(machine, &self.machine_terms, &self.instruments)
    }

    /// The augmented model with the chosen terms added at their selection values.
    pub fn new(
        machine: &MachineGeometry,
        machine_terms: &TermModel,
        instruments: &TermModel,
        setup: &ParameterSetup,
        chosen: &[ChosenTerm],
        prepared: &[Prepared],
    ) -> Result<Self, PhysicsError> {
        let mut out = Self {
            machine_terms: machine_terms.clone(),
            instruments: instruments.clone(),
            setup: setup.clone(),
            added: Vec::new(),
            freed: Vec::new(),
            empirical: Vec::new(),
        };
        for c in chosen {
            match &prepared[c.candidate].source {
                Source::Term { family, kept } => {
                    let v = &family.variants[c.variant];
                    let mut config = v.config.clone();
                    for (name, value, _, _) in &c.parameters {
                        config
                            .params
                            .insert(name.clone(), ConfigValue::Number(*value));
                    }
                    let term = configure(&config)?;
                    let specs = term.term.params();
                    // the separable linear parameters, and the ones the variant fixed by search
                    // (a lag, a lead: refined by the refit); refraction's fixed pressure stays
                    let kept_names: Vec<String> = kept[c.variant]
                        .iter()
                        .map(|&j| specs[j].name.clone())
                        .collect();
                    let searched = specs
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| {
                            !v.linear[*j] && v.profiled > 0 && family.id != TermId::Refraction
                        })
                        .map(|(_, s)| s.name.clone());
                    let free: Vec<String> = kept_names.iter().cloned().chain(searched).collect();
                    let main = kept_names
                        .into_iter()
                        .filter(|n| !crate::candidate_stage::is_nuisance(family.id, n))
                        .collect();
                    let label = term.term.label();
                    match family.placement {
                        Placement::Machine => out.machine_terms.push(term)?,
                        Placement::Instrument => out.instruments.push(term)?,
                    }
                    out.added.push(AddedSource {
                        candidate: c.candidate,
                        config,
                        placement: family.placement,
                        free,
                        main,
                        variant: v.name.clone(),
                        label,
                        id: family.id,
                    });
                }
                Source::Freed { id, label, names } => out.freed.push(FreedSource {
                    candidate: c.candidate,
                    id: *id,
                    label: label.clone(),
                    values: names
                        .iter()
                        .cloned()
                        .zip(c.parameters.iter().map(|p| p.1))
                        .collect(),
                }),
                Source::Empirical(bases) => out.empirical.push(EmpiricalChosen {
                    candidate: c.candidate,
                    basis: bases[c.variant].clone(),
                    coefficients: c.parameters.iter().map(|p| p.1).collect(),
                }),
            }
        }
        let model = out.model(machine)?;
        let added_free: Vec<String> = out
            .added
            .iter()
            .flat_map(|a| a.free.iter().map(move |p| format!("{}.{p}", a.label)))
            .collect();
        let mut setup_aug =
            setup_by_name(&model, setup, &|name| added_free.iter().any(|f| f == name));
        let names = model.param_names();
        for f in &out.freed {
            for (name, _) in &f.values {
                if let Some(k) = names.iter().position(|n| n == name) {
                    setup_aug.free[k] = true;
                }
            }
        }
        out.setup = setup_aug;
        Ok(out)
    }

    /// The start of the refit: the declared fit, the chosen terms at their selection values.
    pub fn start(
        &self,
        machine: &MachineGeometry,
        declared: &ForwardModel,
        x0: &[f64],
    ) -> Result<Vec<f64>, PhysicsError> {
        let model = self.model(machine)?;
        let names_aug = model.param_names();
        let names0 = declared.param_names();
        let mut start: Vec<f64> = model.params();
        for (k, name) in names_aug.iter().enumerate() {
            if let Some(j) = names0.iter().position(|n| n == name) {
                start[k] = x0[j];
            }
            if let Some(v) = self
                .freed
                .iter()
                .flat_map(|f| f.values.iter())
                .find(|(n, _)| n == name)
            {
                start[k] = v.1;
            }
        }
        Ok(start)
    }

    /// The empirical corrections' total at record i of `view` (records frame, m).
    pub fn empirical_at(&self, view: &ResidualView, i: usize) -> Vector3<f64> {
        let mut d = Vector3::zeros();
        for e in &self.empirical {
            d[e.basis.axis] += e
                .basis
                .value(&e.coefficients, view.time[i], &view.position[i]);
        }
        view.rotation(i).transpose() * d
    }

    /// The nonlinear refit from `start`, the empirical corrections (at their selection values)
    /// taken off the measurements; on failure the start is kept and the reason returned.
    pub fn refit(
        &self,
        machine: &MachineGeometry,
        set: &RecordSet,
        view0: &ResidualView,
        start: Vec<f64>,
        options: &DiagnoseOptions,
    ) -> Result<Refit, PhysicsError> {
        let model = self.model(machine)?;
        let mut refit_set = set.clone();
        for (i, r) in refit_set.records.iter_mut().enumerate() {
            r.measured -= self.empirical_at(view0, i);
        }
        // reference nests were placed at the declared fit: with the instrument's terms fitted
        // they are placed again and the fit repeated (a nest's mean reading holds the drift's
        // mean over its readings' times)
        let mut result = fit(
            &model,
            &self.setup,
            &refit_set,
            Some(start.clone()),
            &options.fit,
        );
        if let Ok(f) = &result {
            if refit_set.records.iter().any(is_reference) {
                estimate_nests(&model, &f.x, &mut refit_set.records, &set.frame, true)?;
                let x = f.x.clone();
                result = fit(&model, &self.setup, &refit_set, Some(x), &options.fit);
            }
        }
        Ok(match result {
            Ok(f) => Refit { at_bound: f.parameters.iter().filter_map(|p| p.at_bound.map(|b| (p.name.clone(), b.name().to_string()))).collect(), x: f.x, failure: None },
            Err(e) => Refit { x: start, failure: Some(format!("the nonlinear refit of the augmented model failed ({e}); the selection's linearised values are reported")), at_bound: Vec::new() },
        })
    }
}

/// The refit's result.
pub(crate) struct Refit {
    pub x: Vec<f64>,
    /// Why the refit failed (the start is then kept).
    pub failure: Option<String>,
    /// Parameters (`label.param`) that ended on a bound of their possible range, and which.
    pub at_bound: Vec<(String, String)>,
}
