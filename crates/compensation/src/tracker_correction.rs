//! What the tracker logger corrects in each reading: the air the instrument assumed, and the
//! warm-up it is still in. `metrocell-laser-tracker` (`crates/tracker`, behind the
//! `metrocell-tracker` node) calls `AirData`, `range_for_index` and `warmup_status`;
//! `refraction_corrected_range` is the one-call form of the same correction, used by tests.

use metrocell_physics::instrument::edlen::{birch_downs_index, shop_floor_index};
use metrocell_physics::instrument::tracker_warmup::settling_time;

/// Air at the beam, as a weather station reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirData {
    /// °C
    pub temperature: f64,
    /// Pa
    pub pressure: f64,
    /// relative humidity as a fraction 0..1 (sensor_msgs/RelativeHumidity convention)
    pub humidity: f64,
}

impl AirData {
    /// Refractive index of this air by the shop-floor Edlén equation (thesis eq. 5.5).
    pub fn refractive_index(&self) -> f64 {
        shop_floor_index(self.pressure, self.temperature, self.humidity * 100.0)
    }

    /// Refractive index of this air by the full (Birch & Downs modified) Edlén equation at the
    /// vacuum wavelength `wavelength` (m), e.g. 633e-9 for a HeNe interferometer.
    pub fn refractive_index_full(&self, wavelength: f64) -> f64 {
        birch_downs_index(
            wavelength,
            self.pressure,
            self.temperature,
            self.humidity * 100.0,
        )
    }

    /// Whether every field is finite and physically possible; a station glitch must not
    /// silently rescale every distance.
    pub fn check(&self) -> Result<(), String> {
        if !(self.temperature.is_finite() && (-40.0..=80.0).contains(&self.temperature)) {
            return Err(format!(
                "air temperature {} °C is outside -40..80 °C",
                self.temperature
            ));
        }
        if !(self.pressure.is_finite() && (50e3..=120e3).contains(&self.pressure)) {
            return Err(format!(
                "air pressure {} Pa is outside 50..120 kPa (is it in hPa or kPa?)",
                self.pressure
            ));
        }
        if !(self.humidity.is_finite() && (0.0..=1.0).contains(&self.humidity)) {
            return Err(format!(
                "relative humidity {} is outside 0..1 (is it in percent?)",
                self.humidity
            ));
        }
        Ok(())
    }
}

/// Range re-corrected for the air actually at the beam.
///
/// The instrument measures optical path length and divides by the index it applied, so the
/// geometric range is `r_reported · n_applied / n_actual`. An `n_applied` of 0 means the
/// instrument applied none (it reports optical path / vacuum distance, i.e. n = 1).
pub fn refraction_corrected_range(reported_range: f64, n_applied: f64, air: &AirData) -> f64 {
    range_for_index(reported_range, n_applied, air.refractive_index())
}

/// Range re-corrected from the index the instrument applied (`n_applied`, 0 = none, i.e. 1) to
/// the index `n_actual` of the air at the beam, whichever Edlén form gave it.
pub fn range_for_index(reported_range: f64, n_applied: f64, n_actual: f64) -> f64 {
    let applied = if n_applied == 0.0 { 1.0 } else { n_applied };
    reported_range * applied / n_actual
}

/// Whether a tracker `seconds_since_power_on` after switch-on is still warming up, for a
/// first-order warm-up with time constant `tau` (s): true until 95 % of the drift has settled.
pub fn warmup_status(seconds_since_power_on: f64, tau: f64) -> bool {
    seconds_since_power_on < settling_time(tau, 0.95)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_air_gives_thesis_index() {
        let air = AirData {
            temperature: 20.0,
            pressure: 99_000.0,
            humidity: 0.5,
        };
        assert!((air.refractive_index() - 1.000265156791).abs() < 1e-11);
    }

    #[test]
    fn one_kelvin_error_is_about_one_ppm() {
        // The instrument assumed 20 °C but the air is 21 °C: the range shrinks by ~0.94 ppm.
        let assumed = AirData {
            temperature: 20.0,
            pressure: 101_325.0,
            humidity: 0.5,
        };
        let actual = AirData {
            temperature: 21.0,
            ..assumed
        };
        let r = refraction_corrected_range(5.0, assumed.refractive_index(), &actual);
        let ppm = (r - 5.0) / 5.0 * 1e6;
        assert!((ppm - 0.95).abs() < 0.05, "{ppm} ppm");
    }

    #[test]
    fn no_index_applied_means_vacuum() {
        let air = AirData {
            temperature: 20.0,
            pressure: 101_325.0,
            humidity: 0.5,
        };
        let r = refraction_corrected_range(2.0, 0.0, &air);
        assert!((r - 2.0 / air.refractive_index()).abs() < 1e-15);
    }

    #[test]
    fn full_form_agrees_with_shop_floor_form_to_a_tenth_of_a_ppm() {
        // The shop-floor form is the full form simplified for ~633 nm and shop-floor air.
        let air = AirData {
            temperature: 20.0,
            pressure: 99_000.0,
            humidity: 0.5,
        };
        let d = air.refractive_index_full(633e-9) - air.refractive_index();
        assert!(d.abs() < 1e-7, "full − shop floor = {d:e}");
    }

    #[test]
    fn implausible_air_is_named() {
        let hpa = AirData {
            temperature: 20.0,
            pressure: 1013.25,
            humidity: 0.5,
        };
        assert!(hpa.check().unwrap_err().contains("hPa"));
        let percent = AirData {
            temperature: 20.0,
            pressure: 101_325.0,
            humidity: 50.0,
        };
        assert!(percent.check().unwrap_err().contains("percent"));
        let nan = AirData {
            temperature: f64::NAN,
            pressure: 101_325.0,
            humidity: 0.5,
        };
        assert!(nan.check().is_err());
    }

    #[test]
    fn warmup_ends_at_three_time_constants() {
        // 95 % settling of 1 − e^(−t/τ) is at τ·ln 20 ≈ 3.0 τ.
        assert!(warmup_status(2.9 * 1800.0, 1800.0));
        assert!(!warmup_status(3.1 * 1800.0, 1800.0));
    }
}
