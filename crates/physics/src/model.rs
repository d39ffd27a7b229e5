//! A set of configured terms used together — the simulator's true model, the estimator's
//! declared model, or a declared model plus one `diagnose` candidate. Parameters of all terms
//! are stacked in term order into one vector; names are `label.param`.

use nalgebra::{DMatrix, DVector, Vector3};
use std::collections::BTreeSet;

use crate::catalog::{configure, ConfiguredTerm};
use crate::config::TermConfig;
use crate::error::PhysicsError;
use crate::signals::Signals;
use crate::term::{EffectKind, Frame, ParamSpec};

/// Configured terms with stacked parameters.
#[derive(Debug, Default, Clone)]
pub struct TermModel {
    pub terms: Vec<ConfiguredTerm>,
}

impl TermModel {
    /// Configure every term; labels must be unique (two `positioning[x]` would be one error
    /// counted twice).
    pub fn from_configs(configs: &[TermConfig]) -> Result<Self, PhysicsError> {
        let mut m = TermModel::default();
        for c in configs {
            m.push(configure(c)?)?;
        }
        Ok(m)
    }

    /// Add a term (e.g. a `diagnose` candidate), rejecting a duplicate label.
    pub fn push(&mut self, t: ConfiguredTerm) -> Result<(), PhysicsError> {
        let labels: BTreeSet<String> = self.terms.iter().map(|t| t.term.label()).collect();
        let label = t.term.label();
        if labels.contains(&label) {
            return Err(PhysicsError::InvalidInput {
                what: format!("term model, term `{label}`"),
                reason: "declared twice".into(),
            });
        }
        self.terms.push(t);
        Ok(())
    }

    /// Stacked parameter descriptors, named `label.param`.
    pub fn param_specs(&self) -> Vec<ParamSpec> {
        self.terms
            .iter()
            .flat_map(|t| {
                let label = t.term.label();
                t.term.params().into_iter().map(move |mut p| {
                    p.name = format!("{label}.{}", p.name);
                    p
                })
            })
            .collect()
    }

    /// Stacked configured parameter values.
    pub fn params(&self) -> Vec<f64> {
        self.terms
            .iter()
            .flat_map(|t| t.params.iter().copied())
            .collect()
    }

    fn split<'a>(&self, p: &'a [f64]) -> Result<Vec<&'a [f64]>, PhysicsError> {
        let total: usize = self.terms.iter().map(|t| t.term.params().len()).sum();
        if p.len() != total {
            return Err(PhysicsError::ParameterCount {
                term: "term model".into(),
                expected: total,
                got: p.len(),
            });
        }
        let mut out = Vec::new();
        let mut at = 0;
        for t in &self.terms {
            let n = t.term.params().len();
            out.push(&p[at..at + n]);
            at += n;
        }
        Ok(out)
    }

    /// Sum of the displacements of every term whose effect is `Displacement(frame)`, and its
    /// Jacobian w.r.t. the stacked parameters (zero columns for the other terms).
    pub fn displacement(
        &self,
        frame: Frame,
        p: &[f64],
        s: &Signals,
    ) -> Result<(Vector3<f64>, DMatrix<f64>), PhysicsError> {
        let parts = self.split(p)?;
        let mut d = Vector3::zeros();
        let mut j = DMatrix::zeros(3, p.len());
        let mut col = 0;
        for (t, pt) in self.terms.iter().zip(parts) {
            if t.term.effect() == EffectKind::Displacement(frame) {
                let v: DVector<f64> = t.term.predict(pt, s)?.value;
                d += Vector3::new(v[0], v[1], v[2]);
                j.view_mut((0, col), (3, pt.len()))
                    .copy_from(&t.term.jacobian(pt, s)?);
            }
            col += pt.len();
        }
        Ok((d, j))
    }
}
