//! The one place the thermal corrections build physics [`Signals`]: the point's commanded
//! coordinates (machine frame, also used as the workpiece-frame feature position), the
//! instantaneous sensor temperatures, and for lagged terms the lagged temperature as a
//! one-sample history (the lag itself is advanced incrementally by
//! [`crate::thermal_lag_filter::FirstOrderLag`], so the catalog term sees T_f directly).

use metrocell_physics::{Signals, TemperatureHistory};
use nalgebra::Vector3;

/// `temperatures`: (sensor, °C); `lagged`: (sensor, time s, lagged temperature °C).
pub fn thermal_signals(nominal: &Vector3<f64>, temperatures: &[(&str, f64)], lagged: &[(&str, f64, f64)]) -> Signals {
    let mut s = Signals::default().with_positions(*nominal);
    s.workpiece_point = Some(*nominal);
    for (name, t) in temperatures {
        s.temperatures.insert(name.to_string(), *t);
    }
    for (name, time, tf) in lagged {
        s.temperature_histories.insert(name.to_string(), TemperatureHistory { samples: vec![(*time, *tf)] });
    }
    s
}
