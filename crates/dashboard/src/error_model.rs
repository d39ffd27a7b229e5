//! An ErrorModel as the page shows it: each parameter's value ± σ (σ = √ of the covariance
//! diagonal, row-major N×N) in its SI unit, and the fit's residual RMS.

use metrocell_msgs::msg::ErrorModel;
use serde::Serialize;

use crate::InputError;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelParameter {
    pub name: String,
    pub term: String,
    pub unit: String,
    pub value: f64,
    /// Absent when the model carries no covariance.
    pub sigma: Option<f64>,
}

/// A term instance of the model as its publisher described it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelTerm {
    pub label: String,
    /// Catalog id.
    pub id: String,
    /// Its structural options (axis, order, travel, sensors, …), a JSON object.
    pub options: serde_json::Value,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelView {
    /// Topic it came from.
    pub topic: String,
    pub stamp: f64,
    pub machine_id: String,
    pub parameters: Vec<ModelParameter>,
    /// The term instances (empty when the publisher did not describe them).
    pub terms: Vec<ModelTerm>,
    /// [m]
    pub residual_rms: f64,
    pub observation_count: u32,
    pub degrees_of_freedom: u32,
}

/// Check and convert; a mismatched array length or a negative variance names the field.
pub fn model_view(topic: &str, m: &ErrorModel) -> Result<ModelView, InputError> {
    let n = m.values.len();
    for (field, len) in [
        ("parameter_names", m.parameter_names.len()),
        ("term_ids", m.term_ids.len()),
        ("units", m.units.len()),
    ] {
        if len != n {
            return Err(InputError::new(
                field,
                format!("has {len} entries for {n} values"),
            ));
        }
    }
    if !m.covariance.is_empty() && m.covariance.len() != n * n {
        return Err(InputError::new(
            "covariance",
            format!(
                "has {} entries; {n} values need {}",
                m.covariance.len(),
                n * n
            ),
        ));
    }
    let terms = model_terms(m)?;
    let mut parameters = Vec::with_capacity(n);
    for i in 0..n {
        let sigma = match m.covariance.get(i * n + i) {
            Some(&v) if v >= 0.0 && v.is_finite() => Some(v.sqrt()),
            Some(&v) => {
                return Err(InputError::new(
                    &format!("covariance[{}]", i * n + i),
                    format!("is {v}, not a variance"),
                ))
            }
            None => None,
        };
        parameters.push(ModelParameter {
            name: m.parameter_names[i].clone(),
            term: m.term_ids[i].clone(),
            unit: m.units[i].clone(),
            value: m.values[i],
            sigma,
        });
    }
    Ok(ModelView {
        topic: topic.to_string(),
        stamp: crate::stamp_seconds(&m.header.stamp),
        machine_id: m.machine_id.clone(),
        parameters,
        terms,
        residual_rms: m.residual_rms,
        observation_count: m.observation_count,
        degrees_of_freedom: m.degrees_of_freedom,
    })
}

/// The term descriptions: three arrays of one length, each options entry a JSON object.
fn model_terms(m: &ErrorModel) -> Result<Vec<ModelTerm>, InputError> {
    let n = m.term_labels.len();
    for (field, len) in [
        ("term_catalog_ids", m.term_catalog_ids.len()),
        ("term_options", m.term_options.len()),
    ] {
        if len != n {
            return Err(InputError::new(
                field,
                format!("has {len} entries for {n} term_labels"),
            ));
        }
    }
    (0..n)
        .map(|i| {
            let options: serde_json::Value = serde_json::from_str(&m.term_options[i])
                .ok()
                .filter(serde_json::Value::is_object)
                .ok_or_else(|| {
                    InputError::new(
                        &format!("term_options[{i}]"),
                        format!("is not a JSON object: {}", m.term_options[i]),
                    )
                })?;
            Ok(ModelTerm {
                label: m.term_labels[i].clone(),
                id: m.term_catalog_ids[i].clone(),
                options,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> ErrorModel {
        ErrorModel {
            term_ids: vec!["thermal_scale".into(), "thermal_scale".into()],
            parameter_names: vec![
                "thermal_scale.x.strain".into(),
                "thermal_scale.y.strain".into(),
            ],
            units: vec!["m/m".into(), "m/m".into()],
            values: vec![2.3e-5, -1e-6],
            covariance: vec![4e-12, 1e-13, 1e-13, 9e-14],
            residual_rms: 1.5e-6,
            term_labels: vec!["thermal_scale[x]".into()],
            term_catalog_ids: vec!["thermal_scale".into()],
            term_options: vec![
                r#"{"axis":"x","sensors":[{"name":"x_left","position":0.0}]}"#.into(),
            ],
            ..Default::default()
        }
    }

    #[test]
    fn term_descriptions_are_shown_with_their_options() {
        let v = model_view("t", &model()).unwrap();
        assert_eq!(v.terms.len(), 1);
        assert_eq!(
            (v.terms[0].label.as_str(), v.terms[0].id.as_str()),
            ("thermal_scale[x]", "thermal_scale")
        );
        assert_eq!(v.terms[0].options["sensors"][0]["name"], "x_left");
        let mut m = model();
        m.term_options[0] = "axis: x".into();
        assert_eq!(
            model_view("t", &m).unwrap_err().to_string(),
            "term_options[0] is not a JSON object: axis: x"
        );
        let mut m = model();
        m.term_catalog_ids.clear();
        assert_eq!(
            model_view("t", &m).unwrap_err().to_string(),
            "term_catalog_ids has 0 entries for 1 term_labels"
        );
    }

    #[test]
    fn sigma_is_the_root_of_the_diagonal() {
        let v = model_view("/thermal/error_model", &model()).unwrap();
        assert_eq!(v.parameters[0].sigma, Some(2e-6));
        assert!((v.parameters[1].sigma.unwrap() - 3e-7).abs() < 1e-21);
        assert_eq!(
            (v.parameters[1].name.as_str(), v.parameters[1].unit.as_str()),
            ("thermal_scale.y.strain", "m/m")
        );
        let mut no_cov = model();
        no_cov.covariance.clear();
        assert_eq!(model_view("t", &no_cov).unwrap().parameters[0].sigma, None);
    }

    #[test]
    fn inconsistent_models_name_the_field() {
        let mut m = model();
        m.covariance.pop();
        assert_eq!(
            model_view("t", &m).unwrap_err().to_string(),
            "covariance has 3 entries; 2 values need 4"
        );
        let mut m = model();
        m.units.pop();
        assert_eq!(
            model_view("t", &m).unwrap_err().to_string(),
            "units has 1 entries for 2 values"
        );
        let mut m = model();
        m.covariance[3] = -1.0;
        assert_eq!(
            model_view("t", &m).unwrap_err().to_string(),
            "covariance[3] is -1, not a variance"
        );
    }
}
