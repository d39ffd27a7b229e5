//! What an estimator needs beyond the model: which parameters are free, their priors, and the
//! pairs of parameters that are parallel by construction (their Jacobian columns are equal up
//! to sign at every reading, so only their sum or difference is observable).

use std::collections::BTreeMap;

use metrocell_physics::config::quantity;
use metrocell_physics::{EstimationConfig, PhysicsError, TermId};

use crate::forward::ForwardModel;
use crate::machine::MachineKinematics;

/// Prior of one parameter: value and standard uncertainty, canonical unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    pub value: f64,
    pub sigma: f64,
}

/// Per stacked parameter of a [`ForwardModel`]: its `label.param` name, free or fixed, prior.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterSetup {
    pub names: Vec<String>,
    pub free: Vec<bool>,
    pub priors: Vec<Option<Prior>>,
}

fn invalid(what: String, reason: String) -> PhysicsError {
    PhysicsError::InvalidInput { what, reason }
}

impl ParameterSetup {
    /// Every parameter free, no priors.
    pub fn all_free(model: &ForwardModel) -> Self {
        let names = model.param_names();
        Self {
            free: vec![true; names.len()],
            priors: vec![None; names.len()],
            names,
        }
    }

    /// From `estimation` settings keyed by term label (`positioning[x]`, `tracker_pose`, …);
    /// errors name the key (`estimation.<label>.free`, `estimation.<label>.priors.<param>`).
    pub fn new(
        model: &ForwardModel,
        settings: &BTreeMap<String, EstimationConfig>,
    ) -> Result<Self, PhysicsError> {
        let mut setup = Self::all_free(model);
        let terms: Vec<_> = model
            .machine_terms
            .terms
            .iter()
            .chain(&model.instrument_terms.terms)
            .collect();
        let labels: Vec<String> = terms.iter().map(|t| t.term.label()).collect();
        let mut start = 0;
        let mut starts = Vec::new();
        for t in &terms {
            starts.push(start);
            start += t.params.len();
        }
        for (label, cfg) in settings {
            let key = format!("estimation.{label}");
            let k = labels.iter().position(|l| l == label).ok_or_else(|| {
                invalid(
                    key.clone(),
                    format!("no term has this label; labels: {}", labels.join(", ")),
                )
            })?;
            let specs = terms[k].term.params();
            let allowed = || {
                specs
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let index = |name: &str, what: &str| -> Result<usize, PhysicsError> {
                specs.iter().position(|s| s.name == name).ok_or_else(|| {
                    invalid(
                        format!("{key}.{what}"),
                        format!(
                            "`{name}` is not a parameter of `{label}`; allowed: {}",
                            allowed()
                        ),
                    )
                })
            };
            if let Some(free) = &cfg.free {
                let mut mask = vec![false; specs.len()];
                for name in free {
                    mask[index(name, "free")?] = true;
                }
                setup.free[starts[k]..starts[k] + specs.len()].copy_from_slice(&mask);
            }
            for (name, prior) in &cfg.priors {
                let i = index(name, &format!("priors.{name}"))?;
                let unit = specs[i].unit;
                let at = format!("{key}.priors.{name}");
                let value = quantity(label, &format!("{at}.value"), &prior.value, unit)?;
                let sigma = quantity(label, &format!("{at}.sigma"), &prior.sigma, unit)?;
                if !(value.is_finite() && sigma > 0.0 && sigma.is_finite()) {
                    return Err(invalid(at, format!("needs a finite value and σ > 0 (in {unit}), got value {value}, σ {sigma}")));
                }
                setup.priors[starts[k] + i] = Some(Prior { value, sigma });
            }
        }
        Ok(setup)
    }

    /// Indices of the free parameters in the stacked vector.
    pub fn free_indices(&self) -> Vec<usize> {
        self.free
            .iter()
            .enumerate()
            .filter(|(_, f)| **f)
            .map(|(i, _)| i)
            .collect()
    }
}

/// Two parameters whose effects are parallel by construction, with the sign relating their
/// Jacobian columns (`column(a) = sign·column(b)` at every reading) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ParallelPair {
    pub a: usize,
    pub b: usize,
    pub sign: f64,
    pub reason: &'static str,
}

impl ForwardModel<'_> {
    /// The declared pairs of parallel parameters of this model, per axis k:
    /// * cartesian, delta and five-axis: `positioning[k].c0` (the constant of the series, φ₀ = 1)
    ///   and `tool_offset.dk` both shift the tool point by a constant along machine axis k
    ///   (every reading);
    /// * cartesian and delta: either of those and `frame_misalignment.tk` (a constant shift of
    ///   the part is the opposite shift of the tool relative to it, sign −1; every reading), and
    ///   each tracker's `tracker_pose.tk` (the workpiece frame does not turn, so a constant shift
    ///   of the tool point is a shift of the tracker, sign −1; tracker readings);
    /// * every family: `frame_misalignment.tk` and each tracker's `tracker_pose.tk` (both shift
    ///   the tracker relative to the part, in the workpiece frame, sign +1; tracker readings).
    pub fn parallel_pairs(&self) -> Vec<ParallelPair> {
        let names = self.param_names();
        let find = |n: &str| names.iter().position(|x| x == n);
        let mut pairs = Vec::new();
        let fixed_workpiece = match &self.machine.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) => Some(true),
            MachineKinematics::FiveAxis(_) => Some(false),
            MachineKinematics::SerialArm(_) => None,
        };
        let has_tool_offset = self
            .machine_terms
            .terms
            .iter()
            .any(|t| t.term.id() == TermId::ToolOffset);
        let misalignment = self
            .machine_terms
            .terms
            .iter()
            .find(|t| t.term.id() == TermId::FrameMisalignment)
            .map(|t| t.term.label());
        let tracker_labels: Vec<String> = self
            .instruments()
            .iter()
            .filter_map(|i| i.pose)
            .map(|i| self.term(i).term.label())
            .collect();
        for axis in ["x", "y", "z"] {
            let (c0, d) = match fixed_workpiece {
                Some(_) => (
                    find(&format!("positioning[{axis}].c0")),
                    if has_tool_offset {
                        find(&format!("tool_offset.d{axis}"))
                    } else {
                        None
                    },
                ),
                None => (None, None),
            };
            let fm = misalignment
                .as_ref()
                .and_then(|l| find(&format!("{l}.t{axis}")));
            let trackers: Vec<usize> = tracker_labels
                .iter()
                .filter_map(|l| find(&format!("{l}.t{axis}")))
                .collect();
            if let (Some(a), Some(b)) = (c0, d) {
                pairs.push(ParallelPair { a, b, sign: 1.0, reason: "constant shift of the tool point along a machine axis (positioning series constant vs tool offset)" });
            }
            if fixed_workpiece == Some(true) {
                for x in [c0, d].into_iter().flatten() {
                    if let Some(b) = fm {
                        pairs.push(ParallelPair { a: x, b, sign: -1.0, reason: "constant shift of the tool point vs the opposite shift of the part (frame misalignment)" });
                    }
                    for &b in &trackers {
                        pairs.push(ParallelPair { a: x, b, sign: -1.0, reason: "constant shift of the tool point in the workpiece frame vs the tracker's position (tracker readings)" });
                    }
                }
            }
            if let Some(a) = fm {
                for &b in &trackers {
                    pairs.push(ParallelPair { a, b, sign: 1.0, reason: "the part's translation vs the tracker's position, both in the workpiece frame (tracker readings)" });
                }
            }
        }
        pairs
    }
}
