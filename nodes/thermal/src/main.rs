//! `metrocell-thermal`: thermal drift correction.
//!
//! Subscribes `temperature/<sensor>` (sensor_msgs/Temperature) for every sensor a term reads and
//! `measured_points` (metrocell_msgs/MeasuredPoint); publishes `measured_points/thermal_compensated`
//! with the drift of the configured catalog terms removed and the covariance enlarged:
//! `thermal_scale` α·q·(T(q) − T_ref) per axis (T interpolated between that axis's sensors),
//! `thermal_growth` n·g·(T_f − T_ref) with T_f a first-order lag τ behind its sensor, and
//! `workpiece_expansion` α·(T − T_ref)·(p − clamp). Also a latched `thermal/error_model`
//! (metrocell_msgs/ErrorModel: the parameters in use named `label.param` as the catalog names
//! them, and each scale axis's current strain) and `thermal/predicted_drift` (MeasuredPoint: the
//! drift point and where the terms predict it now). The strains are computed from configured
//! coefficients unless fitted online: a growth term's g and τ from repeated measurements of a
//! reference point (`fit_reference_point`), and the axis scales' α from repeated measurements of
//! reference points on an axis (`fit_alpha_points`, `fit_alpha_axis`: their error along the axis,
//! less every other term's drift, regressed on q·(T(q) − T_ref) by weighted least squares with
//! one static offset per point, see `metrocell_compensation::thermal_scale_fit`). Once enough
//! measurements are in (`fit_min_observations`, `fit_alpha_min_observations`) the fitted values
//! replace the configured ones, the node logs it, and their uncertainty (u(α) from the fit)
//! enters every compensated point's covariance and `thermal/error_model`.
//!
//!   metrocell-thermal --ros-args -p sensors:="[x_left, x_right]" -p sensor_axes:="[x, x]" \
//!       -p sensor_positions:="[0.0, 0.8]" -p alpha:=11.5e-6 \
//!       -p growth_sensors:="[column]" -p growth_directions:="[0.0, 0.0, -1.0]" \
//!       -p growth_coefficients:="[4e-6]" -p growth_time_constants:="[1200.0]"
//!
//! Offline replay (no DDS; inputs from the bag in log-time order, as fast as the CPU allows;
//! outputs to OUT_BAG, or as JSON lines on stdout without `--output`):
//!
//!   metrocell-thermal --bag DEMO_BAG [--output OUT_BAG] --ros-args -p ...

mod live;
mod model_message;
mod parameters;
mod replay;
mod thermal_state;

use metrocell_compensation::GrowthFitResult;
use metrocell_node::{MetrocellNode, Parameters, ReplayArgs};
use nalgebra::Vector3;

use crate::thermal_state::{Settings, ThermalState};

/// The state from the parameters, its configuration logged through `log` (live and replay alike).
fn start(p: &Parameters, log: &dyn Fn(String)) -> Result<ThermalState, Box<dyn std::error::Error>> {
    let (compensator, fit) = parameters::compensator(p)?;
    let alpha_fit = parameters::alpha_fit(p, &compensator)?;
    for line in parameters::describe(&compensator, fit.as_ref(), alpha_fit.as_ref()) {
        log(line);
    }
    let limits = p.get::<Vec<f64>>("temperature_limits")?;
    let d = p.get::<Vec<f64>>("drift_point")?;
    let settings = Settings {
        period_s: p.get::<f64>("publish_period")?,
        stale_after_s: p.get::<f64>("stale_after")?,
        calibration_uncertainty: p.get::<f64>("sensor_calibration_uncertainty")?,
        limits: (limits[0], limits[1]),
        drift_point: Vector3::new(d[0], d[1], d[2]),
    };
    Ok(ThermalState::new(compensator, fit, settings).with_alpha_fit(alpha_fit))
}

/// One log line on a fit of α.
fn describe_alpha_fit(
    state: &ThermalState,
    r: &metrocell_compensation::ScaleFitResult,
    used: bool,
) -> String {
    let (axis, points, min) = state
        .alpha_fit
        .as_ref()
        .map(|a| (["x", "y", "z"][a.axis], a.points.len(), a.min_observations))
        .unwrap_or(("?", 0, 0));
    format!(
        "thermal_scale: fitted alpha = {:.4e} ± {:.2e} 1/K from {} measurements of {points} reference point(s) along {axis} (χ²/dof {:.2}){}",
        r.alpha,
        r.alpha_uncertainty,
        r.observations,
        r.chi2_per_dof(),
        if used { "; using the fitted alpha".to_string() } else { format!("; configured alpha kept until {min} measurements") }
    )
}

/// Log the outcome of a measured point for both online fits.
fn log_fits(
    state: &mut ThermalState,
    p: &metrocell_msgs::msg::MeasuredPoint,
    info: &dyn Fn(String),
    debug: &dyn Fn(String),
) {
    use crate::thermal_state::{AlphaFitEvent, FitEvent};
    match state.reference_measurement(p) {
        Some(FitEvent::Used(r)) => info(describe_fit(state, &r, true)),
        Some(FitEvent::Fitted(r)) => info(describe_fit(state, &r, false)),
        Some(FitEvent::NotYet(why)) => debug(format!("online fit: {why}")),
        None => {}
    }
    match state.alpha_reference_measurement(p) {
        Some(AlphaFitEvent::Used(r)) => info(describe_alpha_fit(state, &r, true)),
        Some(AlphaFitEvent::Fitted(r)) => info(describe_alpha_fit(state, &r, false)),
        Some(AlphaFitEvent::NotYet(why)) => debug(format!("alpha fit: {why}")),
        None => {}
    }
}

/// One log line on a fit of the reference point.
fn describe_fit(state: &ThermalState, r: &GrowthFitResult, used: bool) -> String {
    let label = state
        .fit
        .as_ref()
        .map(|f| state.compensator.growth[f.growth_index].label())
        .unwrap_or_default();
    format!(
        "{label}: fitted g = {:.4} ± {:.4} µm/K, τ = {:.0} ± {:.0} s from {} reference measurements (rms {:.2} µm){}",
        r.coefficient * 1e6,
        r.covariance[(1, 1)].sqrt() * 1e6,
        r.time_constant,
        r.covariance[(2, 2)].sqrt(),
        r.observations,
        r.rms * 1e6,
        if used { "; using the fitted values" } else if r.at_bound { "; τ at the end of its range, configured values kept" } else { "; configured values kept until enough measurements" }
    )
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-thermal: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (builder, rest) = MetrocellNode::builder("thermal")
        .params(parameters::declarations())
        .node_argument(ReplayArgs::FLAG, ReplayArgs::HELP)
        .args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay::run(builder.build_offline()?, &args),
        None => live::run(builder.build()?),
    }
}
