//! The node's parameters.

use metrocell_dashboard_state::{AlertThresholds, StateConfig};
use metrocell_node::{ParamDecl, Parameters};

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new(
            "port",
            8765i64,
            "TCP port of the web page, /api/state and /ws (0: any free port)",
        )
        .with_range(0.0, 65535.0),
        ParamDecl::new(
            "foxglove_port",
            8766i64,
            "TCP port of the Foxglove WebSocket server (0: any free port, -1: off)",
        )
        .with_range(-1.0, 65535.0),
        ParamDecl::new(
            "bind_address",
            "127.0.0.1".to_string(),
            "address both servers listen on (localhost only unless told otherwise)",
        ),
        ParamDecl::new(
            "window",
            3600.0,
            "drift-fit and plot window [s of cell time]",
        )
        .with_range(1.0, 7.0 * 86400.0),
        ParamDecl::new(
            "max_samples",
            20000i64,
            "samples kept per series (bounds memory over a shift)",
        )
        .with_range(10.0, 1e7),
        ParamDecl::new(
            "plot_points",
            400i64,
            "points per plotted series sent to the page",
        )
        .with_range(10.0, 1e5),
        ParamDecl::new(
            "push_period",
            0.25,
            "seconds between WebSocket pushes to the page",
        )
        .with_range(0.02, 60.0),
        ParamDecl::new(
            "alert_period",
            1.0,
            "seconds between alert publications on /diagnostics",
        )
        .with_range(0.05, 3600.0),
        ParamDecl::new(
            "error_warn_um",
            20.0,
            "WARN when the predicted volumetric error exceeds this [µm]",
        )
        .with_range(0.0, 1e6),
        ParamDecl::new(
            "error_error_um",
            50.0,
            "ERROR when the predicted volumetric error exceeds this [µm]",
        )
        .with_range(0.0, 1e6),
        ParamDecl::new(
            "drift_warn_um_per_h",
            10.0,
            "WARN when an axis drifts faster than this [µm/h]",
        )
        .with_range(0.0, 1e9),
        ParamDecl::new(
            "drift_error_um_per_h",
            30.0,
            "ERROR when an axis drifts faster than this [µm/h]",
        )
        .with_range(0.0, 1e9),
        ParamDecl::new(
            "alert_coverage_k",
            2.0,
            "a level is raised when |value| − k·σ exceeds its threshold",
        )
        .with_range(0.0, 10.0),
        ParamDecl::new(
            "min_drift_span",
            600.0,
            "shortest window [s] over which a drift rate is judged",
        )
        .with_range(0.0, 86400.0),
        ParamDecl::new(
            "finding_prefixes",
            vec!["diagnose".to_string()],
            "DiagnosticStatus name prefixes shown as findings",
        ),
        ParamDecl::new(
            "points_topics",
            vec![
                "measured_points".to_string(),
                "measured_points/thermal_compensated".to_string(),
            ],
            "metrocell_msgs/MeasuredPoint topics whose volumetric error is shown and alerted on",
        ),
        ParamDecl::new(
            "model_topics",
            vec![
                "thermal/error_model".to_string(),
                "estimator/error_model".to_string(),
            ],
            "metrocell_msgs/ErrorModel topics",
        ),
        ParamDecl::new(
            "temperature_namespace",
            "temperature".to_string(),
            "every sensor_msgs/Temperature topic under it is a sensor",
        ),
        ParamDecl::new(
            "tracker_topic",
            "tracker/measurements".to_string(),
            "metrocell_msgs/TrackerMeasurement topic",
        ),
    ]
}

pub fn state_config(p: &Parameters) -> Result<StateConfig, Box<dyn std::error::Error>> {
    Ok(StateConfig {
        window: p.get::<f64>("window")?,
        max_samples: p.get::<i64>("max_samples")? as usize,
        plot_points: p.get::<i64>("plot_points")? as usize,
        thresholds: AlertThresholds::from_um(
            p.get::<f64>("error_warn_um")?,
            p.get::<f64>("error_error_um")?,
            p.get::<f64>("drift_warn_um_per_h")?,
            p.get::<f64>("drift_error_um_per_h")?,
            p.get::<f64>("alert_coverage_k")?,
            p.get::<f64>("min_drift_span")?,
        )?,
        finding_prefixes: p.get::<Vec<String>>("finding_prefixes")?,
    })
}
