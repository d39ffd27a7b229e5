//! The node's parameters and the messages built from its state.

use metrocell_compensation::thermal_scale_compensation::Reading;
use metrocell_compensation::{AxisSensorPlacement, ThermalError, ThermalScaleCompensator};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::ErrorModel;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{ParamDecl, Parameters};

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("sensors", Vec::<String>::new(), "sensor names; each is read from temperature/<name>"),
        ParamDecl::new("sensor_axes", Vec::<String>::new(), "axis (x, y or z) each sensor sits on, same order as sensors"),
        ParamDecl::new("sensor_positions", Vec::<f64>::new(), "axis coordinate of each sensor [m], same order as sensors"),
        ParamDecl::new("alpha", 11.5e-6, "expansion coefficient of the axis scales [1/K] (steel 11.5e-6)").with_range(0.0, 5e-5),
        ParamDecl::new("alpha_uncertainty", 1.0e-6, "standard uncertainty of alpha [1/K]").with_range(0.0, 5e-5),
        ParamDecl::new("reference_temperature", 20.0, "temperature at which the scales are true [°C] (ISO 1: 20)")
            .with_range(-10.0, 60.0),
        ParamDecl::new("publish_period", 1.0, "seconds between thermal/error_model messages").with_range(0.01, 3600.0),
        ParamDecl::new("stale_after", 10.0, "a sensor silent for longer than this [s] is not used").with_range(0.1, 86400.0),
    ]
}

/// The compensator from the start-up parameters (live node: `node.parameters()`; replay: the offline node's).
pub fn compensator(node: &Parameters) -> Result<ThermalScaleCompensator, Box<dyn std::error::Error>> {
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
            other => return Err(format!("parameter sensor_axes: sensor '{name}' has axis '{other}'; allowed: x, y, z").into()),
        };
        placements.push(AxisSensorPlacement { name, axis, position });
    }
    Ok(ThermalScaleCompensator::new(
        node.get::<f64>("alpha")?,
        node.get::<f64>("alpha_uncertainty")?,
        node.get::<f64>("reference_temperature")?,
        placements,
    )?)
}

/// The current strain of every covered axis as an ErrorModel (term thermal_scale, unit m/m).
pub fn error_model(c: &ThermalScaleCompensator, reading: &dyn Fn(&str) -> Option<Reading>, now_ns: i64) -> Result<ErrorModel, ThermalError> {
    let mut m = ErrorModel {
        header: Header {
            stamp: Time::from_nanos(now_ns),
            frame_id: "machine".into(),
        },
        machine_id: String::new(),
        ..Default::default()
    };
    let mut variances = Vec::new();
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        if !c.covers(k) {
            continue;
        }
        let (strain, var) = c.axis_strain(k, reading)?;
        m.term_ids.push("thermal_scale".into());
        m.parameter_names.push(format!("thermal_scale.{axis}.strain"));
        m.units.push("m/m".into());
        m.values.push(strain);
        variances.push(var);
        m.observation_count += c.sensors().iter().filter(|s| s.axis == k).count() as u32;
    }
    let n = variances.len();
    m.covariance = vec![0.0; n * n];
    for (i, v) in variances.iter().enumerate() {
        m.covariance[i * n + i] = *v;
    }
    Ok(m)
}

/// One log line describing the configuration.
pub fn describe(c: &ThermalScaleCompensator) -> String {
    format!(
        "alpha={:e} 1/K ± {:e}, T_ref={} °C, sensors: {}",
        c.alpha,
        c.alpha_uncertainty,
        c.reference_temperature,
        c.sensors().iter().map(|s| format!("{}@{}{:+.3}m", s.name, ["x", "y", "z"][s.axis], s.position)).collect::<Vec<_>>().join(", ")
    )
}
