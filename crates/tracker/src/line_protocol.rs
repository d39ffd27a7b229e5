//! The ASCII line framing the TCP driver reads (one reading per line, UTF-8, `\n` or `\r\n`):
//!
//! ```text
//! <t_s>,<target>,<range_m>,<azimuth_rad>,<elevation_rad>[,<air_temperature_degC>,<air_pressure_Pa>,<relative_humidity_0_1>]
//! 1732500000.100,nest_1,2.000013,0.523599,0.104720,20.1,101325,0.45
//! ```
//!
//! * `t_s`: the instrument's time stamp in seconds (ROS epoch, i.e. Unix time), strictly
//!   increasing; a reading whose time is not after the last accepted one is a repeat (after a
//!   reconnect the instrument may resend its buffer) and is dropped.
//! * `target`: SMR or nest name, no comma; empty while the target moves.
//! * `range_m` as the instrument reports it (divided by the index it applied, a node parameter);
//!   `nan` or `BREAK` means a beam break.
//! * the air triple is optional: the instrument's weather station.
//! * empty lines and lines starting with `#` are ignored; lines longer than
//!   [`MAX_LINE_BYTES`] or not UTF-8 are garbage.
//!
//! Values are only parsed here; whether they are plausible (angles in range, air physical) is
//! decided by [`crate::reading::ReadingProcessor`].

use metrocell_compensation::AirData;

use crate::reading::{RawReading, STATUS_BEAM_BREAK};
use crate::total_station_gsi::GsiError;

pub const MAX_LINE_BYTES: usize = 1024;

/// One parsed line.
#[derive(Debug, Clone, PartialEq)]
pub struct LineReading {
    pub t: f64,
    pub target: String,
    pub range: f64,
    pub azimuth: f64,
    pub elevation: f64,
    pub air: Option<AirData>,
    pub beam_break: bool,
}

impl LineReading {
    /// As a [`RawReading`] for the processor; `applied_index` is the index the instrument
    /// divided its ranges by (0 = none).
    pub fn to_raw(&self, applied_index: f64) -> RawReading {
        RawReading {
            time_ns: (self.t * 1e9).round() as i64,
            target: self.target.clone(),
            range: self.range,
            azimuth: self.azimuth,
            elevation: self.elevation,
            refractive_index: applied_index,
            air: self.air,
            status: if self.beam_break {
                STATUS_BEAM_BREAK
            } else {
                0
            },
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LineError {
    #[error("line longer than {MAX_LINE_BYTES} bytes")]
    TooLong,
    #[error("line is not UTF-8")]
    NotUtf8,
    #[error("line has {0} fields; expected 5 or 8 (t,target,range,azimuth,elevation[,T,p,RH])")]
    FieldCount(usize),
    #[error("field {field} = '{text}' is not a number")]
    NotANumber { field: &'static str, text: String },
    #[error("time stamp {0} is not finite")]
    BadTime(f64),
    /// A total station's line that is not a GSI block (the line, cut to 120 characters).
    #[error("line '{line}': {error}")]
    Gsi { line: String, error: GsiError },
}

/// Parse one line (without its terminator). `Ok(None)` for blank and comment lines.
pub fn parse_line(line: &str) -> Result<Option<LineReading>, LineError> {
    let line = line.trim_end_matches('\r').trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let f: Vec<&str> = line.split(',').map(str::trim).collect();
    if f.len() != 5 && f.len() != 8 {
        return Err(LineError::FieldCount(f.len()));
    }
    let num = |field: &'static str, text: &str| {
        text.parse::<f64>().map_err(|_| LineError::NotANumber {
            field,
            text: text.chars().take(40).collect(),
        })
    };
    let t = num("t", f[0])?;
    if !t.is_finite() {
        return Err(LineError::BadTime(t));
    }
    let beam_break = f[2].eq_ignore_ascii_case("break");
    let range = if beam_break {
        f64::NAN
    } else {
        num("range", f[2])?
    };
    let air = if f.len() == 8 {
        Some(AirData {
            temperature: num("air_temperature", f[5])?,
            pressure: num("air_pressure", f[6])?,
            humidity: num("relative_humidity", f[7])?,
        })
    } else {
        None
    };
    Ok(Some(LineReading {
        t,
        target: f[1].to_string(),
        range,
        azimuth: num("azimuth", f[3])?,
        elevation: num("elevation", f[4])?,
        air,
        beam_break: beam_break || range.is_nan(),
    }))
}

/// Splits a byte stream into lines, keeping a partial line until its end arrives.
#[derive(Debug, Default)]
pub struct LineFramer {
    partial: Vec<u8>,
    discarding: bool,
}

impl LineFramer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feed received bytes; returns every complete line (or why it is garbage).
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Result<String, LineError>> {
        let mut out = Vec::new();
        for &b in bytes {
            if b == b'\n' {
                if std::mem::take(&mut self.discarding) {
                    out.push(Err(LineError::TooLong));
                } else {
                    let line = std::mem::take(&mut self.partial);
                    out.push(String::from_utf8(line).map_err(|_| LineError::NotUtf8));
                }
                self.partial.clear();
            } else if !self.discarding {
                self.partial.push(b);
                if self.partial.len() > MAX_LINE_BYTES {
                    self.discarding = true;
                    self.partial.clear();
                }
            }
        }
        out
    }

    /// Forget a partial line (the connection that carried it is gone).
    pub fn reset(&mut self) {
        self.partial.clear();
        self.discarding = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::approx_constant)] // 0.5236 is a reading on the wire, not a rounded π/6
    fn full_and_short_lines_parse() {
        let r = parse_line("1732500000.1,nest_1,2.000013,0.5236,0.1047,20.1,101325,0.45\r")
            .unwrap()
            .unwrap();
        assert_eq!(
            (r.t, r.target.as_str(), r.range, r.azimuth, r.elevation),
            (1732500000.1, "nest_1", 2.000013, 0.5236, 0.1047)
        );
        assert_eq!(
            r.air,
            Some(AirData {
                temperature: 20.1,
                pressure: 101325.0,
                humidity: 0.45
            })
        );
        let r = parse_line("5, ,1.5,0,0").unwrap().unwrap();
        assert_eq!((r.target.as_str(), r.air, r.beam_break), ("", None, false));
        assert!(parse_line("6,p,BREAK,0,0").unwrap().unwrap().beam_break);
        assert!(parse_line("6,p,nan,0,0").unwrap().unwrap().beam_break);
        assert_eq!(parse_line("# header"), Ok(None));
        assert_eq!(parse_line("  "), Ok(None));
    }

    #[test]
    fn garbage_is_named() {
        assert_eq!(parse_line("1,p,2,3"), Err(LineError::FieldCount(4)));
        assert_eq!(
            parse_line("1,p,2.x,0,0"),
            Err(LineError::NotANumber {
                field: "range",
                text: "2.x".into()
            })
        );
        assert_eq!(
            parse_line("inf,p,2,0,0"),
            Err(LineError::BadTime(f64::INFINITY))
        );
        assert!(matches!(
            parse_line("1,p,2,0,0,20,abc,0.5"),
            Err(LineError::NotANumber {
                field: "air_pressure",
                ..
            })
        ));
    }

    #[test]
    fn framer_keeps_partial_lines_and_drops_overlong_ones() {
        let mut f = LineFramer::new();
        assert!(f.feed(b"1,a,2,0").is_empty());
        assert_eq!(f.feed(b",0\n2,b"), vec![Ok("1,a,2,0,0".to_string())]);
        assert_eq!(f.feed(b",3,0,0\n"), vec![Ok("2,b,3,0,0".to_string())]);
        let long = vec![b'x'; MAX_LINE_BYTES + 10];
        assert!(f.feed(&long).is_empty());
        assert_eq!(
            f.feed(b"yy\n3,c,1,0,0\n"),
            vec![Err(LineError::TooLong), Ok("3,c,1,0,0".to_string())]
        );
        assert_eq!(f.feed(&[0xff, 0xfe, b'\n']), vec![Err(LineError::NotUtf8)]);
        f.feed(b"4,d");
        f.reset();
        assert_eq!(f.feed(b"5,e,1,0,0\n"), vec![Ok("5,e,1,0,0".to_string())]);
    }
}
