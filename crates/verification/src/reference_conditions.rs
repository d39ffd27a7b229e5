//! The conditions a verification's error map is stated at: the reference temperature of ISO 1
//! (20 °C) at every temperature sensor, everything else as at one of the readings.
//!
//! Why: a model with thermal terms (an axis's scale expanding with its temperature, a column
//! growing with its own) predicts a different error at every instant of a shift. The map a
//! metrologist signs and a controller compensates is the machine's geometry; the thermal terms'
//! identified coefficients say what temperature adds to it. At 20 °C every catalog thermal term
//! with the default reference temperature contributes nothing, so the map is the geometric
//! errors alone. A lagging term (`thermal_growth` with `lag: true`) reads the sensor's history:
//! the history given here is 20 °C throughout, so its filtered temperature is 20 °C too.

use std::sync::Arc;

use metrocell_physics::{Signals, TemperatureTimeline};

/// ISO 1's reference temperature for dimensional measurement, °C.
pub const REFERENCE_TEMPERATURE: f64 = 20.0;

/// `reading`'s signals with every temperature sensor it names at [`REFERENCE_TEMPERATURE`]
/// (its latest value and its whole history). Signals without temperatures are returned as
/// they are.
pub fn at_reference_temperature(reading: &Signals) -> Signals {
    let mut s = reading.clone();
    let mut sensors: Vec<String> = s.temperatures.keys().cloned().collect();
    if let Some(t) = &s.timeline {
        sensors.extend(t.sensors());
    }
    sensors.sort();
    sensors.dedup();
    if sensors.is_empty() {
        return s;
    }
    let time = s.time.unwrap_or(0.0);
    let timeline = TemperatureTimeline::new();
    for name in &sensors {
        s.temperatures.insert(name.clone(), REFERENCE_TEMPERATURE);
        timeline.add_sensor(name);
        // one sample at the instant: the history is flat at the reference temperature
        timeline
            .push(name, time, REFERENCE_TEMPERATURE)
            .expect("a finite sample into an empty series");
    }
    s.timeline = Some(Arc::new(timeline));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sensor_and_its_history_read_the_reference_temperature() {
        let timeline = TemperatureTimeline::new();
        timeline.add_sensor("column");
        timeline.push("column", 10.0, 23.0).unwrap();
        timeline.push("column", 20.0, 24.0).unwrap();
        let s = Signals {
            time: Some(20.0),
            temperatures: [("table".to_string(), 21.5)].into_iter().collect(),
            timeline: Some(Arc::new(timeline)),
            ..Signals::default()
        };
        let r = at_reference_temperature(&s);
        assert_eq!(r.temperatures["table"], 20.0);
        assert_eq!(r.temperatures["column"], 20.0);
        let t = r.timeline.as_ref().unwrap();
        let mut names = t.sensors();
        names.sort();
        assert_eq!(names, vec!["column".to_string(), "table".to_string()]);
        // the original is untouched
        assert_eq!(s.temperatures["table"], 21.5);
    }

    #[test]
    fn signals_without_temperatures_are_unchanged() {
        let s = Signals {
            time: Some(3.0),
            ..Signals::default()
        };
        let r = at_reference_temperature(&s);
        assert!(r.temperatures.is_empty() && r.timeline.is_none());
    }
}
