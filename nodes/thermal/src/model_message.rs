//! The messages built from the compensator's state: `thermal/error_model` (the catalog
//! parameters in use, named `label.param` as the physics catalog names them, plus each scale
//! axis's current mean strain `thermal_scale[x].strain`) and `thermal/predicted_drift` (the drift
//! of the configured drift point).

use metrocell_compensation::{GrowthFitResult, Reading, ThermalCompensator, ThermalError};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_physics::ConfiguredTerm;
use nalgebra::{DMatrix, Vector3};

fn header(now_ns: i64) -> Header {
    Header {
        stamp: Time::from_nanos(now_ns),
        frame_id: "machine".into(),
    }
}

/// Entries with a covariance block per term.
struct Builder {
    m: ErrorModel,
    blocks: Vec<DMatrix<f64>>,
}

impl Builder {
    /// Describe a term instance (label, catalog id, options) for consumers that rebuild it.
    fn describe(&mut self, t: &ConfiguredTerm) {
        self.m.term_labels.push(t.term.label());
        self.m
            .term_catalog_ids
            .push(t.term.id().as_str().to_string());
        self.m.term_options.push(t.options_json());
    }

    fn push(&mut self, term: &str, names: Vec<(String, &str, f64)>, cov: DMatrix<f64>) {
        for (name, unit, value) in names {
            self.m.term_ids.push(term.into());
            self.m.parameter_names.push(name);
            self.m.units.push(unit.into());
            self.m.values.push(value);
        }
        self.blocks.push(cov);
    }
}

pub fn error_model(
    c: &ThermalCompensator,
    fit: Option<&(GrowthFitResult, bool)>,
    reading: &dyn Fn(&str) -> Option<Reading>,
    now_ns: i64,
) -> Result<ErrorModel, ThermalError> {
    let mut b = Builder {
        m: ErrorModel {
            header: header(now_ns),
            machine_id: String::new(),
            ..Default::default()
        },
        blocks: Vec::new(),
    };
    let s = &c.scale;
    for (k, label) in s.labels() {
        if let Some(t) = s.axis_term(k) {
            b.describe(t);
        }
        let (strain, var) = s.axis_strain(k, reading)?;
        b.push(
            "thermal_scale",
            vec![(format!("{label}.alpha"), "1/K", s.alpha)],
            DMatrix::from_element(1, 1, s.alpha_uncertainty.powi(2)),
        );
        b.push(
            "thermal_scale",
            vec![(format!("{label}.strain"), "m/m", strain)],
            DMatrix::from_element(1, 1, var),
        );
        b.m.observation_count += s.sensors().iter().filter(|p| p.axis == k).count() as u32;
    }
    for g in &c.growth {
        b.describe(g.catalog_term());
        let label = g.label();
        let (params, cov) = g.parameters();
        let n = params.len();
        let names = params
            .into_iter()
            .map(|(name, unit, v)| (format!("{label}.{name}"), unit, v))
            .collect();
        b.push(
            "thermal_growth",
            names,
            DMatrix::from_fn(n, n, |i, j| cov[(i, j)]),
        );
    }
    if let Some(w) = &c.workpiece {
        b.describe(w.catalog_term());
        b.push(
            "workpiece_expansion",
            vec![(format!("{}.alpha", w.label()), "1/K", w.alpha)],
            DMatrix::from_element(1, 1, w.alpha_uncertainty.powi(2)),
        );
    }
    if let Some((r, _)) = fit {
        b.m.residual_rms = r.rms;
        b.m.observation_count += r.observations as u32;
        b.m.degrees_of_freedom = r.observations.saturating_sub(3) as u32;
    }
    let n = b.m.values.len();
    b.m.covariance = vec![0.0; n * n];
    let mut at = 0;
    for blk in &b.blocks {
        for i in 0..blk.nrows() {
            for j in 0..blk.ncols() {
                b.m.covariance[(at + i) * n + at + j] = blk[(i, j)];
            }
        }
        at += blk.nrows();
    }
    Ok(b.m)
}

/// Where the drift point is predicted to be: nominal = the drift point, measured = it plus the
/// predicted thermal drift (machine frame, m), covariance of the drift (m²).
pub fn predicted_drift(
    c: &ThermalCompensator,
    point: &Vector3<f64>,
    reading: &dyn Fn(&str) -> Option<Reading>,
    now_ns: i64,
) -> Result<MeasuredPoint, ThermalError> {
    let (d, cov) = c.drift(point, reading)?;
    let mut covariance = [0.0; 9];
    covariance.copy_from_slice(cov.transpose().as_slice());
    Ok(MeasuredPoint {
        header: header(now_ns),
        point_id: "predicted_drift".into(),
        source: "thermal".into(),
        nominal: Point {
            x: point.x,
            y: point.y,
            z: point.z,
        },
        measured: Point {
            x: point.x + d.x,
            y: point.y + d.y,
            z: point.z + d.z,
        },
        covariance,
    })
}
