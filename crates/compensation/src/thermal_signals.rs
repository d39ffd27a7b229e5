//! The one place the thermal corrections build physics [`Signals`]: the point's commanded
//! coordinates (machine frame, also used as the workpiece-frame feature position), the
//! instantaneous sensor temperatures, and for lagged terms the lagged temperature as a
//! one-sample timeline at the instant's time (the lag itself is advanced incrementally by
//! [`metrocell_physics::thermal::first_order_lag::FirstOrderLag`], so the catalog term sees T_f
//! directly).

use std::sync::Arc;

use metrocell_physics::{Signals, TemperatureTimeline};
use nalgebra::Vector3;

/// `temperatures`: (sensor, °C); `lagged`: (sensor, time s, lagged temperature °C).
pub fn thermal_signals(
    nominal: &Vector3<f64>,
    temperatures: &[(&str, f64)],
    lagged: &[(&str, f64, f64)],
) -> Signals {
    let mut s = Signals::default().with_positions(*nominal);
    s.workpiece_point = Some(*nominal);
    for (name, t) in temperatures {
        s.temperatures.insert(name.to_string(), *t);
    }
    if !lagged.is_empty() {
        let timeline = TemperatureTimeline::new();
        for (name, time, tf) in lagged {
            // one sample per sensor: it cannot be out of order; a non-finite one is left out
            // and the term then reports the sensor as missing
            let _ = timeline.push(name, *time, *tf);
        }
        s.timeline = Some(Arc::new(timeline));
    }
    s
}
