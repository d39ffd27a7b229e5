//! The node's parameters and the compensator they configure.

use metrocell_compensation::{
    AxisSensorPlacement, GrowthCompensator, GrowthFit, GrowthSpec, ScaleFit, ThermalCompensator,
    ThermalScaleCompensator, WorkpieceCompensator,
};
use metrocell_node::{ParamDecl, Parameters};
use nalgebra::Vector3;

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("sensors", Vec::<String>::new(), "axis-scale sensor names; each is read from temperature/<name>"),
        ParamDecl::new("sensor_axes", Vec::<String>::new(), "axis (x, y or z) each scale sensor sits on, same order as sensors"),
        ParamDecl::new("sensor_positions", Vec::<f64>::new(), "axis coordinate of each scale sensor [m], same order as sensors"),
        ParamDecl::new("alpha", 11.5e-6, "configured expansion coefficient of the axis scales [1/K] (steel 11.5e-6; catalog range -2e-6..3e-5); replaced by the online fit when fit_alpha_points is set and enough measurements fit").with_range(-2e-6, 3e-5),
        ParamDecl::new("alpha_uncertainty", 1.0e-6, "standard uncertainty of alpha [1/K] (ISO/TR 230-9 rule for steel: 5.77e-7)").with_range(0.0, 5e-5),
        ParamDecl::new("reference_temperature", 20.0, "temperature at which the scales are true [°C] (ISO 1: 20)")
            .with_range(-10.0, 60.0),
        ParamDecl::new("publish_period", 1.0, "seconds between thermal/error_model and thermal/predicted_drift messages").with_range(0.01, 3600.0),
        ParamDecl::new("stale_after", 10.0, "a sensor silent for longer than this [s] is not used").with_range(0.1, 86400.0),
        metrocell_node::diagnostics::input_timeout_param(),
        ParamDecl::new("sensor_calibration_uncertainty", 0.0, "standard calibration uncertainty of every sensor [K], added to each reading's variance (not averaged down by a lag)").with_range(0.0, 10.0),
        ParamDecl::new("temperature_limits", vec![-20.0, 80.0], "[min, max] °C: readings outside are rejected"),
        ParamDecl::new("growth_sensors", Vec::<String>::new(), "one thermal_growth term per sensor (structure growth d = n·g·(T_f − T_ref))"),
        ParamDecl::new("growth_directions", Vec::<f64>::new(), "growth direction n of each growth term, 3 numbers per sensor (machine frame)"),
        ParamDecl::new("growth_coefficients", Vec::<f64>::new(), "g = L·α of each growth term [m/K]"),
        ParamDecl::new("growth_coefficient_uncertainties", Vec::<f64>::new(), "u(g) of each growth term [m/K] (empty: 10 % of g)"),
        ParamDecl::new("growth_time_constants", Vec::<f64>::new(), "first-order lag τ of each growth term behind its sensor [s]; 0 = no lag"),
        ParamDecl::new("growth_time_constant_uncertainties", Vec::<f64>::new(), "u(τ) of each growth term [s] (empty: 10 % of τ)"),
        ParamDecl::new("workpiece_sensor", String::new(), "sensor on the workpiece/artefact; empty = no workpiece_expansion term"),
        ParamDecl::new("workpiece_clamp", vec![0.0, 0.0, 0.0], "clamp point the workpiece expands about [m], machine frame"),
        ParamDecl::new("workpiece_alpha", 11.5e-6, "configured expansion coefficient of the workpiece [1/K]").with_range(-2e-6, 3e-5),
        ParamDecl::new("workpiece_alpha_uncertainty", 5.77e-7, "u(α) of the workpiece [1/K] (ISO/TR 230-9: 0.0006 µm/(mm·K))").with_range(0.0, 5e-5),
        ParamDecl::new("drift_point", vec![0.0, 0.0, 0.0], "point [m] whose predicted thermal drift is published on thermal/predicted_drift"),
        ParamDecl::new("fit_reference_point", Vec::<f64>::new(), "nominal [m] of a reference point measured repeatedly; its measurements fit g and τ of a growth term (empty = no fit)"),
        ParamDecl::new("fit_reference_tolerance", 1e-4, "a measured point whose nominal is within this distance [m] of fit_reference_point (or of a fit_alpha_points point) is that reference").with_range(1e-9, 1.0),
        ParamDecl::new("fit_growth_sensor", String::new(), "growth term whose g and τ are fitted (its sensor; empty = the only growth term)"),
        ParamDecl::new("fit_min_observations", 8i64, "reference measurements needed before the fitted values replace the configured ones").with_range(4.0, 1e6),
        ParamDecl::new("fit_time_constant_range", vec![60.0, 1e5], "[min, max] s searched for τ"),
        ParamDecl::new("fit_interval", 60.0, "least time [s, message stamps] between refits of g and τ, and between log lines of the alpha fit; every reference measurement enters the next fit (a refit re-runs the lag over the whole window)").with_range(0.0, 86400.0),
        ParamDecl::new("fit_alpha_points", Vec::<f64>::new(), "nominals of reference points on the fitted axis, measured repeatedly, x y z per point [m] (flat list; far from the axis origin is best: the lever is q·(T(q) − T_ref)); their errors along fit_alpha_axis fit the scales' alpha by weighted least squares, with one static offset per point (empty = no alpha fit)"),
        ParamDecl::new("fit_alpha_axis", "x".to_string(), "axis (x, y or z, with scale sensors) whose error at the fit_alpha_points is regressed on q·(T(q) − T_ref); the fitted alpha is then used for every axis (the node has one alpha)").with_allowed(["x", "y", "z"]),
        ParamDecl::new("fit_alpha_min_observations", 20i64, "measurements of the fit_alpha_points needed before the fitted alpha (and its uncertainty, which then enters every point's covariance) replaces alpha and alpha_uncertainty").with_range(3.0, 1e9),
    ]
}

/// The online fit of the scales' α as configured.
pub struct AlphaFitConfig {
    pub fit: ScaleFit,
    /// 0, 1, 2 = x, y, z
    pub axis: usize,
    /// nominals of the reference points, m
    pub points: Vec<Vector3<f64>>,
    pub tolerance: f64,
    pub min_observations: usize,
    /// s between log lines
    pub interval: f64,
}

impl AlphaFitConfig {
    /// Index of the reference point whose nominal is within the tolerance of `nominal` (the nearest).
    pub fn point_index(&self, nominal: &Vector3<f64>) -> Option<usize> {
        self.points
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (p - nominal).norm()))
            .filter(|(_, d)| *d <= self.tolerance)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }
}

/// The α fit from the start-up parameters, if `fit_alpha_points` is set.
pub fn alpha_fit(
    node: &Parameters,
    c: &ThermalCompensator,
) -> Result<Option<AlphaFitConfig>, Box<dyn std::error::Error>> {
    let flat = node.get::<Vec<f64>>("fit_alpha_points")?;
    if flat.is_empty() {
        return Ok(None);
    }
    if flat.len() % 3 != 0 || flat.iter().any(|v| !v.is_finite()) {
        return Err(err(
            "fit_alpha_points",
            format!("needs finite x y z triples in m, got {} values", flat.len()),
        ));
    }
    let axis_name = node.get::<String>("fit_alpha_axis")?;
    let axis = ["x", "y", "z"]
        .iter()
        .position(|a| *a == axis_name)
        .ok_or_else(|| err("fit_alpha_axis", format!("'{axis_name}'; allowed: x, y, z")))?;
    if !c.scale.covers(axis) {
        return Err(err("fit_alpha_axis", format!("axis {axis_name} has no scale sensor (sensors / sensor_axes): there is no thermal_scale term to fit")));
    }
    let points: Vec<Vector3<f64>> = flat
        .chunks(3)
        .map(|v| Vector3::new(v[0], v[1], v[2]))
        .collect();
    Ok(Some(AlphaFitConfig {
        fit: ScaleFit::new(points.len()).map_err(|e| err("fit_alpha_points", e))?,
        axis,
        points,
        tolerance: node.get::<f64>("fit_reference_tolerance")?,
        min_observations: node.get::<i64>("fit_alpha_min_observations")? as usize,
        interval: node.get::<f64>("fit_interval")?,
    }))
}

/// The reference-point fit as configured.
pub struct FitConfig {
    pub fit: GrowthFit,
    /// index into `ThermalCompensator::growth`
    pub growth_index: usize,
    pub point: Vector3<f64>,
    pub tolerance: f64,
    pub min_observations: usize,
    /// s between refits
    pub interval: f64,
}

fn err(name: &str, reason: impl std::fmt::Display) -> Box<dyn std::error::Error> {
    format!("parameter {name}: {reason}").into()
}

fn vector3(p: &Parameters, name: &str) -> Result<Option<Vector3<f64>>, Box<dyn std::error::Error>> {
    let v = p.get::<Vec<f64>>(name)?;
    match v.len() {
        0 => Ok(None),
        3 if v.iter().all(|x| x.is_finite()) => Ok(Some(Vector3::new(v[0], v[1], v[2]))),
        _ => Err(err(
            name,
            format!("needs 3 finite numbers [x, y, z] in m, got {v:?}"),
        )),
    }
}

/// One value per growth sensor, or a default per sensor when the list is empty.
fn per_growth_sensor(
    p: &Parameters,
    name: &str,
    n: usize,
    default: impl Fn(usize) -> Option<f64>,
) -> Result<Vec<f64>, Box<dyn std::error::Error>> {
    let v = p.get::<Vec<f64>>(name)?;
    if v.is_empty() {
        return (0..n)
            .map(|i| {
                default(i)
                    .ok_or_else(|| err(name, format!("needs {n} values, one per growth sensor")))
            })
            .collect();
    }
    if v.len() != n {
        return Err(err(
            name,
            format!("has {} values but growth_sensors has {n}", v.len()),
        ));
    }
    if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
        return Err(err(name, format!("value {bad} is not finite")));
    }
    Ok(v)
}

/// The compensator and the optional fit from the start-up parameters (live node:
/// `node.parameters()`; replay: the offline node's).
pub fn compensator(
    node: &Parameters,
) -> Result<(ThermalCompensator, Option<FitConfig>), Box<dyn std::error::Error>> {
    let names = node.get::<Vec<String>>("sensors")?;
    let axes = node.get::<Vec<String>>("sensor_axes")?;
    let positions = node.get::<Vec<f64>>("sensor_positions")?;
    if axes.len() != names.len() || positions.len() != names.len() {
        return Err(format!(
            "parameters sensors ({}), sensor_axes ({}) and sensor_positions ({}) must have the same length",
            names.len(),
            axes.len(),
            positions.len()
        )
        .into());
    }
    let mut placements = Vec::new();
    for ((name, axis), position) in names.into_iter().zip(axes).zip(positions) {
        let axis = match axis.as_str() {
            "x" | "X" => 0,
            "y" | "Y" => 1,
            "z" | "Z" => 2,
            other => {
                return Err(format!(
                    "parameter sensor_axes: sensor '{name}' has axis '{other}'; allowed: x, y, z"
                )
                .into())
            }
        };
        placements.push(AxisSensorPlacement {
            name,
            axis,
            position,
        });
    }
    let reference_temperature = node.get::<f64>("reference_temperature")?;
    let scale = ThermalScaleCompensator::new(
        node.get::<f64>("alpha")?,
        node.get::<f64>("alpha_uncertainty")?,
        reference_temperature,
        placements,
    )
    .map_err(|e| err("alpha / sensors", e))?;

    let calibration = node.get::<f64>("sensor_calibration_uncertainty")?;
    let growth_sensors = node.get::<Vec<String>>("growth_sensors")?;
    let n = growth_sensors.len();
    let directions = node.get::<Vec<f64>>("growth_directions")?;
    if directions.len() != 3 * n {
        return Err(err(
            "growth_directions",
            format!(
                "needs 3 numbers per growth sensor ({}), got {}",
                3 * n,
                directions.len()
            ),
        ));
    }
    let coefficients = per_growth_sensor(node, "growth_coefficients", n, |_| None)?;
    let u_coefficients = per_growth_sensor(node, "growth_coefficient_uncertainties", n, |i| {
        Some(0.1 * coefficients[i].abs())
    })?;
    let taus = per_growth_sensor(node, "growth_time_constants", n, |_| Some(0.0))?;
    let u_taus = per_growth_sensor(node, "growth_time_constant_uncertainties", n, |i| {
        Some(0.1 * taus[i])
    })?;
    let mut growth = Vec::new();
    for (i, sensor) in growth_sensors.iter().enumerate() {
        if taus[i] < 0.0 {
            return Err(err(
                "growth_time_constants",
                format!(
                    "sensor '{sensor}': τ = {} s must be ≥ 0 (0 = no lag)",
                    taus[i]
                ),
            ));
        }
        let spec = GrowthSpec {
            sensor: sensor.clone(),
            direction: Vector3::new(
                directions[3 * i],
                directions[3 * i + 1],
                directions[3 * i + 2],
            ),
            coefficient: coefficients[i],
            coefficient_uncertainty: u_coefficients[i],
            time_constant: (taus[i] > 0.0).then_some(taus[i]),
            time_constant_uncertainty: u_taus[i],
            reference_temperature,
            calibration_uncertainty: calibration,
        };
        growth.push(GrowthCompensator::new(spec).map_err(|e| err("growth_*", e))?);
    }

    let workpiece_sensor = node.get::<String>("workpiece_sensor")?;
    let workpiece = if workpiece_sensor.is_empty() {
        None
    } else {
        let clamp = vector3(node, "workpiece_clamp")?
            .ok_or_else(|| err("workpiece_clamp", "needs [x, y, z] in m"))?;
        Some(
            WorkpieceCompensator::new(
                &workpiece_sensor,
                clamp,
                node.get::<f64>("workpiece_alpha")?,
                node.get::<f64>("workpiece_alpha_uncertainty")?,
                reference_temperature,
            )
            .map_err(|e| err("workpiece_*", e))?,
        )
    };
    let compensator = ThermalCompensator {
        scale,
        growth,
        workpiece,
    };

    let limits = node.get::<Vec<f64>>("temperature_limits")?;
    if !(limits.len() == 2 && limits[0] < limits[1]) {
        return Err(err(
            "temperature_limits",
            format!("needs [min, max] °C with min < max, got {limits:?}"),
        ));
    }
    vector3(node, "drift_point")?.ok_or_else(|| err("drift_point", "needs [x, y, z] in m"))?;

    let fit = match vector3(node, "fit_reference_point")? {
        None => None,
        Some(point) => {
            let wanted = node.get::<String>("fit_growth_sensor")?;
            let growth_index = if wanted.is_empty() {
                if compensator.growth.len() != 1 {
                    return Err(err(
                        "fit_growth_sensor",
                        format!(
                            "names the growth term to fit; there are {} growth terms",
                            compensator.growth.len()
                        ),
                    ));
                }
                0
            } else {
                compensator
                    .growth
                    .iter()
                    .position(|g| g.spec.sensor == wanted)
                    .ok_or_else(|| {
                        err(
                            "fit_growth_sensor",
                            format!("'{wanted}' is not in growth_sensors"),
                        )
                    })?
            };
            let g = &compensator.growth[growth_index];
            if g.spec.time_constant.is_none() {
                return Err(err("fit_growth_sensor", format!("growth term '{}' has no lag (growth_time_constants 0); the fit is of g and τ", g.spec.sensor)));
            }
            let range = node.get::<Vec<f64>>("fit_time_constant_range")?;
            if range.len() != 2 {
                return Err(err(
                    "fit_time_constant_range",
                    format!("needs [min, max] s, got {range:?}"),
                ));
            }
            let fit = GrowthFit::new(
                g.spec.direction,
                reference_temperature,
                (range[0], range[1]),
                500_000,
            )
            .map_err(|e| err("fit_*", e))?;
            Some(FitConfig {
                fit,
                growth_index,
                point,
                tolerance: node.get::<f64>("fit_reference_tolerance")?,
                min_observations: node.get::<i64>("fit_min_observations")? as usize,
                interval: node.get::<f64>("fit_interval")?,
            })
        }
    };
    Ok((compensator, fit))
}

/// Log lines describing the configuration: which values are configured and which are fitted.
pub fn describe(
    c: &ThermalCompensator,
    fit: Option<&FitConfig>,
    alpha_fit: Option<&AlphaFitConfig>,
) -> Vec<String> {
    let s = &c.scale;
    let mut lines = vec![if s.sensors().is_empty() {
        "thermal_scale: no axis-scale sensors configured".to_string()
    } else {
        format!(
        "thermal_scale: strain computed from the configured alpha={:e} 1/K ± {:e} ({}), T_ref={} °C, sensors: {}",
        s.alpha,
        s.alpha_uncertainty,
        if alpha_fit.is_some() { "fitted online, see below" } else { "not estimated" },
        s.reference_temperature,
        s.sensors().iter().map(|p| format!("{}@{}{:+.3}m", p.name, ["x", "y", "z"][p.axis], p.position)).collect::<Vec<_>>().join(", ")
    )
    }];
    for g in &c.growth {
        let lag = g.spec.time_constant.map_or("no lag".to_string(), |t| {
            format!("lag τ={t} s ± {} s", g.spec.time_constant_uncertainty)
        });
        lines.push(format!(
            "{}: configured g={:e} m/K ± {:e}, {lag}, direction [{:.3}, {:.3}, {:.3}]",
            g.label(),
            g.spec.coefficient,
            g.spec.coefficient_uncertainty,
            g.spec.direction.x,
            g.spec.direction.y,
            g.spec.direction.z
        ));
    }
    if let Some(w) = &c.workpiece {
        lines.push(format!(
            "{}: configured alpha={:e} 1/K ± {:e}, clamp [{}, {}, {}] m",
            w.label(),
            w.alpha,
            w.alpha_uncertainty,
            w.clamp.x,
            w.clamp.y,
            w.clamp.z
        ));
    }
    if let Some(f) = fit {
        lines.push(format!(
            "online fit: g and τ of {} from the reference point [{}, {}, {}] m; the fitted values replace the configured ones after {} measurements",
            c.growth[f.growth_index].label(),
            f.point.x,
            f.point.y,
            f.point.z,
            f.min_observations
        ));
    }
    if let Some(a) = alpha_fit {
        lines.push(format!(
            "online fit: alpha of the axis scales from the {} error of {} reference point(s) [{}] m against q·(T(q) − T_ref); the fitted alpha replaces the configured one after {} measurements",
            ["x", "y", "z"][a.axis],
            a.points.len(),
            a.points.iter().map(|p| format!("({}, {}, {})", p.x, p.y, p.z)).collect::<Vec<_>>().join(", "),
            a.min_observations
        ));
    }
    lines
}
