//! The messages built from the filter: `estimator/error_model` (every machine-term parameter of
//! the model, named `label.param` with the catalog's SI unit, the covariance of the free ones,
//! zero rows and columns for the fixed ones, and each term instance described so a consumer can
//! rebuild it) and `estimator/predicted_error` (the volumetric error at configured joints).

use metrocell_estimation::RecursiveEstimator;
use metrocell_model::ForwardModel;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::diagnostic_msgs::msg::{DiagnosticArray, DiagnosticStatus, KeyValue};
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::std_msgs::msg::Header;
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::estimator_state::Alarm;
use crate::observability_watch::ObservabilityNote;

fn header(ns: i64) -> Header {
    Header {
        stamp: Time::from_nanos(ns),
        frame_id: "machine".into(),
    }
}

/// The machine terms' part of the filter's state (instrument terms are nuisance parameters of
/// the measured points' frame and are not published). `unobserved` directions of the free
/// parameters are not counted as estimated in the degrees of freedom.
pub fn error_model(
    model: &ForwardModel,
    filter: &RecursiveEstimator,
    machine_id: &str,
    stamp_ns: i64,
    unobserved: usize,
) -> ErrorModel {
    let terms = &model.machine_terms.terms;
    let specs = model.machine_terms.param_specs();
    let n = specs.len();
    let x = filter.state();
    let free = filter.free_indices();
    let p = filter.covariance();
    let mut covariance = vec![0.0; n * n];
    for (i, &a) in free.iter().enumerate().filter(|(_, &a)| a < n) {
        for (j, &b) in free.iter().enumerate().filter(|(_, &b)| b < n) {
            covariance[a * n + b] = p[(i, j)];
        }
    }
    let mut term_ids = Vec::with_capacity(n);
    for t in terms {
        term_ids.extend(std::iter::repeat_n(
            t.term.id().as_str().to_string(),
            t.params.len(),
        ));
    }
    let (accepted, _, _) = filter.counts();
    ErrorModel {
        header: header(stamp_ns),
        machine_id: machine_id.to_string(),
        term_ids,
        parameter_names: specs.iter().map(|s| s.name.clone()).collect(),
        units: specs.iter().map(|s| s.unit.to_string()).collect(),
        values: x[..n].to_vec(),
        covariance,
        residual_rms: filter.innovation_rms(),
        observation_count: accepted as u32,
        degrees_of_freedom: (3 * accepted)
            .saturating_sub(free.len().saturating_sub(unobserved) as u64)
            as u32,
        term_labels: terms.iter().map(|t| t.term.label()).collect(),
        term_catalog_ids: terms
            .iter()
            .map(|t| t.term.id().as_str().to_string())
            .collect(),
        term_options: terms.iter().map(|t| t.options_json()).collect(),
    }
}

/// J·P·Jᵀ over the free parameters: the covariance of a quantity with Jacobian `jacobian`
/// (3 × stacked parameters) w.r.t. the state.
pub fn propagate(jacobian: &DMatrix<f64>, filter: &RecursiveEstimator) -> Matrix3<f64> {
    let free = filter.free_indices();
    let j = DMatrix::from_fn(3, free.len(), |r, c| jacobian[(r, free[c])]);
    let c = &j * filter.covariance() * j.transpose();
    Matrix3::from_fn(|r, k| c[(r, k)])
}

/// Point `k`'s prediction: nominal and true tool point (m), covariance of the error (m²).
pub fn predicted_point(
    k: usize,
    nominal: &Vector3<f64>,
    truth: &Vector3<f64>,
    covariance: &Matrix3<f64>,
    stamp_ns: i64,
) -> MeasuredPoint {
    let mut cov = [0.0; 9];
    cov.copy_from_slice(covariance.transpose().as_slice());
    MeasuredPoint {
        header: header(stamp_ns),
        point_id: format!("predicted_{k}"),
        source: "estimator".into(),
        nominal: Point {
            x: nominal.x,
            y: nominal.y,
            z: nominal.z,
        },
        measured: Point {
            x: truth.x,
            y: truth.y,
            z: truth.z,
        },
        covariance: cov,
    }
}

/// The alarm as a `/diagnostics` message (level ERROR, named after the node): where the model
/// stopped explaining the data and how improbable the recent innovations were under it.
pub fn alarm_message(a: &Alarm, node_fqn: &str) -> DiagnosticArray {
    let kv = |key: &str, value: String| KeyValue {
        key: key.into(),
        value,
    };
    DiagnosticArray {
        header: header(a.stamp_ns),
        status: vec![DiagnosticStatus {
            level: DiagnosticStatus::ERROR,
            name: node_fqn.to_string(),
            message: format!(
                "the model stopped explaining the data at point {} (measurement {}): moving χ² tail probability {:.1e}, innovation [{:.1}, {:.1}, {:.1}] µm; the covariance re-opened along what the data inform (at most to the prior) to re-converge",
                a.point_id,
                a.measurement,
                a.window_probability,
                a.innovation.x * 1e6,
                a.innovation.y * 1e6,
                a.innovation.z * 1e6
            ),
            hardware_id: String::new(),
            values: vec![
                kv("alarm_point", a.point_id.clone()),
                kv("alarm_measurement", a.measurement.to_string()),
                kv("alarm_nis", format!("{:.3}", a.nis)),
                kv("alarm_window_probability", format!("{:.3e}", a.window_probability)),
                kv("alarm_innovation_um", format!("[{:.2}, {:.2}, {:.2}]", a.innovation.x * 1e6, a.innovation.y * 1e6, a.innovation.z * 1e6)),
            ],
        }],
    }
}

/// What the estimator holds as a `/diagnostics` message: WARN naming the parameters the data do
/// not observe (held at their start values) and those held at an edge of their possible range;
/// OK once every free parameter is observed again.
pub fn observability_message(note: &ObservabilityNote, node_fqn: &str) -> DiagnosticArray {
    let kv = |key: &str, value: &[String]| KeyValue {
        key: key.into(),
        value: value.join(", "),
    };
    let (level, message) = match &note.text {
        Some(text) => (DiagnosticStatus::WARN, format!("{text}; give them priors or fix them in the model's estimation: section, or measure where they show")),
        None => (DiagnosticStatus::OK, "every free parameter is observed by the measurements".to_string()),
    };
    DiagnosticArray {
        header: header(note.stamp_ns),
        status: vec![DiagnosticStatus {
            level,
            name: node_fqn.to_string(),
            message,
            hardware_id: String::new(),
            values: vec![
                kv("unobservable", &note.unobservable),
                kv("at_bound", &note.at_bound),
            ],
        }],
    }
}
