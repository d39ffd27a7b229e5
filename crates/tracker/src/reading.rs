//! One tracker reading: refraction re-correction, beam breaks, bad values, covariance.
//!
//! Spherical convention: that of `metrocell_compensation::spherical` (and of
//! `metrocell_msgs/TrackerMeasurement`), tracker frame right-handed, z up, azimuth from +x
//! towards +y, elevation above the xy plane. The range the instrument reports was divided by
//! the index it applied (`refractive_index`, 0 = none); it is re-corrected here with the index
//! of the air the node believes is at the beam.

use metrocell_compensation::{range_for_index, spherical_to_cartesian, AirData, SphericalNoise};
use nalgebra::{Matrix3, Vector3};

/// The status bit a tracker sets when the beam is interrupted (as `TrackerMeasurement`).
pub const STATUS_BEAM_BREAK: u8 = 1;

/// A reading as an instrument reports it.
#[derive(Debug, Clone, PartialEq)]
pub struct RawReading {
    /// Measurement time, ns (node clock or the instrument's, converted by the caller).
    pub time_ns: i64,
    /// SMR or nest name; empty while the target moves.
    pub target: String,
    /// m, divided by `refractive_index` by the instrument
    pub range: f64,
    /// rad
    pub azimuth: f64,
    /// rad
    pub elevation: f64,
    /// Index the instrument applied; 0 when none (vacuum distance).
    pub refractive_index: f64,
    /// The instrument's weather-station air, when it reports one.
    pub air: Option<AirData>,
    /// Status bits as `TrackerMeasurement::STATUS_*`.
    pub status: u8,
}

/// Which Edlén equation gives the index of the air.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EdlenForm {
    /// NIST shop-floor form (thesis eq. 8): ~1e-7 over shop-floor air, no wavelength needed.
    ShopFloor,
    /// Birch & Downs modified Edlén at this vacuum wavelength (m).
    Full { wavelength: f64 },
}

/// Where the air at the beam comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AirSource {
    /// The air each reading carries (the tracker's weather station, or the station topics the
    /// node merged in); a reading without air is rejected.
    Station,
    /// Fixed air values (a controlled lab, or a station the instrument does not report).
    Configured(AirData),
}

/// Why a reading gives no point.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReadingError {
    #[error("beam break on target '{0}'")]
    BeamBreak(String),
    #[error("{field} = {value} is not finite")]
    NotFinite { field: &'static str, value: f64 },
    #[error("{field} = {value} is outside {min}..{max}")]
    OutOfRange {
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("air at the beam rejected: {0}")]
    Air(String),
    #[error("no air data in the reading and no configured air (parameter air_source)")]
    NoAir,
}

/// A reading turned into a point.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcessedReading {
    pub time_ns: i64,
    pub target: String,
    /// m, for the air at the beam
    pub range: f64,
    pub azimuth: f64,
    pub elevation: f64,
    /// index used for `range`
    pub refractive_index: f64,
    pub air: AirData,
    /// tracker frame, m
    pub point: Vector3<f64>,
    /// m², from the spherical noise model at `range`
    pub covariance: Matrix3<f64>,
}

/// The per-reading processing configured once.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadingProcessor {
    pub noise: SphericalNoise,
    pub air: AirSource,
    pub form: EdlenForm,
    /// m: longest range the instrument can measure; anything beyond is garbage
    pub max_range: f64,
}

impl ReadingProcessor {
    /// Index of `air` by the configured Edlén form.
    pub fn index(&self, air: &AirData) -> f64 {
        match self.form {
            EdlenForm::ShopFloor => air.refractive_index(),
            EdlenForm::Full { wavelength } => air.refractive_index_full(wavelength),
        }
    }

    /// Radial standard deviation at `range`: a + b·range.
    pub fn radial_sigma(&self, range: f64) -> f64 {
        self.noise.radial_sigma(range)
    }

    pub fn process(&self, r: &RawReading) -> Result<ProcessedReading, ReadingError> {
        if r.status & STATUS_BEAM_BREAK != 0 || r.range.is_nan() {
            return Err(ReadingError::BeamBreak(r.target.clone()));
        }
        finite("range", r.range)?;
        finite("azimuth", r.azimuth)?;
        finite("elevation", r.elevation)?;
        finite("refractive_index", r.refractive_index)?;
        if r.range <= 0.0 {
            return Err(ReadingError::OutOfRange {
                field: "range",
                value: r.range,
                min: 0.0,
                max: self.max_range,
            });
        }
        within("range", r.range, 0.0, self.max_range)?;
        within(
            "azimuth",
            r.azimuth,
            -2.0 * std::f64::consts::PI,
            2.0 * std::f64::consts::PI,
        )?;
        within(
            "elevation",
            r.elevation,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        )?;
        if r.refractive_index != 0.0 {
            // an applied index outside this is not air: a unit or field-order mistake
            within("refractive_index", r.refractive_index, 1.0, 1.001)?;
        }
        let air = match (self.air, r.air) {
            (AirSource::Configured(a), _) => a,
            (AirSource::Station, Some(a)) => a,
            (AirSource::Station, None) => return Err(ReadingError::NoAir),
        };
        air.check().map_err(ReadingError::Air)?;
        let n = self.index(&air);
        let range = range_for_index(r.range, r.refractive_index, n);
        let (point, covariance) =
            spherical_to_cartesian(range, r.azimuth, r.elevation, &self.noise);
        Ok(ProcessedReading {
            time_ns: r.time_ns,
            target: r.target.clone(),
            range,
            azimuth: r.azimuth,
            elevation: r.elevation,
            refractive_index: n,
            air,
            point,
            covariance,
        })
    }
}

fn finite(field: &'static str, value: f64) -> Result<(), ReadingError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ReadingError::NotFinite { field, value })
    }
}

fn within(field: &'static str, value: f64, min: f64, max: f64) -> Result<(), ReadingError> {
    if (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(ReadingError::OutOfRange {
            field,
            value,
            min,
            max,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thesis_air() -> AirData {
        AirData {
            temperature: 20.0,
            pressure: 99_000.0,
            humidity: 0.5,
        }
    }

    fn processor() -> ReadingProcessor {
        ReadingProcessor {
            noise: SphericalNoise {
                radial_base: 4e-6,
                radial_per_metre: 0.8e-6,
                angular: 3e-6,
            },
            air: AirSource::Station,
            form: EdlenForm::ShopFloor,
            max_range: 80.0,
        }
    }

    fn raw() -> RawReading {
        RawReading {
            time_ns: 5,
            target: "nest".into(),
            range: 2.0,
            azimuth: 0.3,
            elevation: 0.1,
            refractive_index: 1.00027,
            air: Some(thesis_air()),
            status: 0,
        }
    }

    #[test]
    fn thesis_index_at_99_kpa_20_c_50_percent() {
        let n = processor().index(&thesis_air());
        assert!((n - 1.000265156791).abs() < 1e-11, "{n}");
    }

    #[test]
    fn range_is_recorrected_for_the_station_air() {
        let p = processor().process(&raw()).unwrap();
        let expected = 2.0 * 1.00027 / 1.000265156792;
        assert!(
            (p.range - expected).abs() < 1e-12,
            "{} vs {expected}",
            p.range
        );
        // (1.00027 − 1.000265157)/1 ≈ 4.84 ppm → 9.69 µm at 2 m
        assert!(
            ((p.range - 2.0) * 1e6 - 9.686).abs() < 0.01,
            "{} µm",
            (p.range - 2.0) * 1e6
        );
    }

    #[test]
    fn full_form_is_used_when_configured() {
        let full = ReadingProcessor {
            form: EdlenForm::Full { wavelength: 633e-9 },
            ..processor()
        };
        let p = full.process(&raw()).unwrap();
        assert_eq!(
            p.refractive_index,
            thesis_air().refractive_index_full(633e-9)
        );
        assert!((p.range - 2.0 * 1.00027 / p.refractive_index).abs() < 1e-15);
    }

    #[test]
    fn covariance_is_the_spherical_noise_model() {
        let p = processor().process(&raw()).unwrap();
        // radial variance along the line of sight = (a + b·r)²
        let u = p.point / p.point.norm();
        let radial = (u.transpose() * p.covariance * u)[(0, 0)].sqrt();
        assert!(
            (radial - (4e-6 + 0.8e-6 * p.range)).abs() < 1e-9,
            "{radial}"
        );
    }

    #[test]
    fn beam_breaks_and_bad_values_are_named() {
        let mut b = raw();
        b.status = STATUS_BEAM_BREAK;
        assert_eq!(
            processor().process(&b),
            Err(ReadingError::BeamBreak("nest".into()))
        );
        let nan = RawReading {
            range: f64::NAN,
            ..raw()
        };
        assert!(matches!(
            processor().process(&nan),
            Err(ReadingError::BeamBreak(_))
        ));
        let az = RawReading {
            azimuth: f64::INFINITY,
            ..raw()
        };
        assert_eq!(
            processor().process(&az),
            Err(ReadingError::NotFinite {
                field: "azimuth",
                value: f64::INFINITY
            })
        );
        let el = RawReading {
            elevation: 2.0,
            ..raw()
        };
        assert!(matches!(
            processor().process(&el),
            Err(ReadingError::OutOfRange {
                field: "elevation",
                ..
            })
        ));
        let far = RawReading {
            range: 120.0,
            ..raw()
        };
        assert!(matches!(
            processor().process(&far),
            Err(ReadingError::OutOfRange { field: "range", .. })
        ));
        let neg = RawReading {
            range: -1.0,
            ..raw()
        };
        assert!(matches!(
            processor().process(&neg),
            Err(ReadingError::OutOfRange { field: "range", .. })
        ));
        let hpa = RawReading {
            air: Some(AirData {
                pressure: 990.0,
                ..thesis_air()
            }),
            ..raw()
        };
        assert!(processor()
            .process(&hpa)
            .unwrap_err()
            .to_string()
            .contains("hPa"));
        let none = RawReading { air: None, ..raw() };
        assert_eq!(processor().process(&none), Err(ReadingError::NoAir));
        let configured = ReadingProcessor {
            air: AirSource::Configured(thesis_air()),
            ..processor()
        };
        assert!(configured.process(&none).is_ok());
    }
}
