//! Units of parameter values: parsing of quantities written with a unit suffix
//! ("12 um", "1.2e-5 1/K", "20 degC", "0.5 mrad") and the dimension check that rejects
//! a unit that does not match the parameter's dimension.
//!
//! A unit string is a product of atoms separated by `*`, `·` or spaces, with at most one `/`
//! (everything after it is in the denominator); an atom may carry an integer exponent
//! (`m^2`, `s^-1`). Angles (`rad`), pixels (`px`) and relative humidity (`%RH`) are kept as
//! their own base dimensions so that, e.g., `mrad` is never accepted for a length.
//! Temperatures: `degC` (also `°C`, `C`) and `K` share the temperature dimension; an absolute
//! temperature parameter (canonical unit `degC`) given in `K` is converted with the 273.15 offset,
//! anywhere else `K` and `degC` are both temperature *differences* (scale 1).

use std::fmt;

/// Exponents of the base dimensions: metre, kilogram, second, kelvin, radian, pixel, %RH.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Dimension {
    pub m: i8,
    pub kg: i8,
    pub s: i8,
    pub k: i8,
    pub rad: i8,
    pub px: i8,
    pub rh: i8,
}

impl Dimension {
    fn scaled(self, e: i8) -> Self {
        Self {
            m: self.m * e,
            kg: self.kg * e,
            s: self.s * e,
            k: self.k * e,
            rad: self.rad * e,
            px: self.px * e,
            rh: self.rh * e,
        }
    }
    fn plus(self, o: Self) -> Self {
        Self {
            m: self.m + o.m,
            kg: self.kg + o.kg,
            s: self.s + o.s,
            k: self.k + o.k,
            rad: self.rad + o.rad,
            px: self.px + o.px,
            rh: self.rh + o.rh,
        }
    }
    /// Human name used in error messages.
    pub fn describe(&self) -> String {
        let named: &[(Dimension, &str)] = &[
            (Dimension::default(), "a dimensionless ratio"),
            (
                Dimension {
                    m: 1,
                    ..Default::default()
                },
                "length",
            ),
            (
                Dimension {
                    rad: 1,
                    ..Default::default()
                },
                "angle",
            ),
            (
                Dimension {
                    s: 1,
                    ..Default::default()
                },
                "time",
            ),
            (
                Dimension {
                    k: 1,
                    ..Default::default()
                },
                "temperature",
            ),
            (
                Dimension {
                    k: -1,
                    ..Default::default()
                },
                "inverse temperature",
            ),
            (
                Dimension {
                    m: 1,
                    k: -1,
                    ..Default::default()
                },
                "length per kelvin",
            ),
            (
                Dimension {
                    kg: 1,
                    m: -1,
                    s: -2,
                    ..Default::default()
                },
                "pressure",
            ),
            (
                Dimension {
                    rh: 1,
                    ..Default::default()
                },
                "relative humidity",
            ),
        ];
        for (d, n) in named {
            if d == self {
                return (*n).to_string();
            }
        }
        format!("{self}")
    }
}

impl fmt::Display for Dimension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts = [
            ("m", self.m),
            ("kg", self.kg),
            ("s", self.s),
            ("K", self.k),
            ("rad", self.rad),
            ("px", self.px),
            ("%RH", self.rh),
        ];
        let s: Vec<String> = parts
            .iter()
            .filter(|(_, e)| *e != 0)
            .map(|(n, e)| {
                if *e == 1 {
                    n.to_string()
                } else {
                    format!("{n}^{e}")
                }
            })
            .collect();
        if s.is_empty() {
            write!(f, "1")
        } else {
            write!(f, "{}", s.join("·"))
        }
    }
}

/// A parsed unit: value_in_SI = scale · value + offset (offset only for absolute temperatures).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    pub dimension: Dimension,
    pub scale: f64,
    /// True when the unit is a bare `K` (kelvin) — matters only for absolute temperatures.
    pub is_kelvin: bool,
}

fn atom(name: &str) -> Option<(Dimension, f64)> {
    let d = |m, kg, s, k, rad, px, rh| Dimension {
        m,
        kg,
        s,
        k,
        rad,
        px,
        rh,
    };
    let len = d(1, 0, 0, 0, 0, 0, 0);
    let ang = d(0, 0, 0, 0, 1, 0, 0);
    let time = d(0, 0, 1, 0, 0, 0, 0);
    let temp = d(0, 0, 0, 1, 0, 0, 0);
    let pres = d(-1, 1, -2, 0, 0, 0, 0);
    let one = Dimension::default();
    Some(match name {
        "1" | "" => (one, 1.0),
        "m" => (len, 1.0),
        "km" => (len, 1e3),
        "cm" => (len, 1e-2),
        "mm" => (len, 1e-3),
        "um" | "µm" | "μm" | "micron" => (len, 1e-6),
        "nm" => (len, 1e-9),
        "rad" => (ang, 1.0),
        "mrad" => (ang, 1e-3),
        "urad" | "µrad" | "μrad" => (ang, 1e-6),
        "deg" | "°" => (ang, std::f64::consts::PI / 180.0),
        "arcsec" => (ang, std::f64::consts::PI / 180.0 / 3600.0),
        "s" => (time, 1.0),
        "ms" => (time, 1e-3),
        "us" | "µs" | "μs" => (time, 1e-6),
        "min" => (time, 60.0),
        "h" => (time, 3600.0),
        "d" => (time, 86_400.0),
        "Hz" => (d(0, 0, -1, 0, 0, 0, 0), 1.0),
        "kHz" => (d(0, 0, -1, 0, 0, 0, 0), 1e3),
        "K" | "degC" | "°C" | "C" => (temp, 1.0),
        "Pa" => (pres, 1.0),
        "hPa" | "mbar" => (pres, 100.0),
        "kPa" => (pres, 1e3),
        "N" => (d(1, 1, -2, 0, 0, 0, 0), 1.0),
        "kg" => (d(0, 1, 0, 0, 0, 0, 0), 1.0),
        "ppm" => (one, 1e-6),
        "%" | "percent" => (one, 1e-2),
        "%RH" | "RH" => (d(0, 0, 0, 0, 0, 0, 1), 1.0),
        "px" | "pixel" => (d(0, 0, 0, 0, 0, 1, 0), 1.0),
        _ => return None,
    })
}

/// Parse a unit expression such as `um`, `1/K`, `rad/(N m)`, `m/N`, `1/(N m^2)`, `um/m`.
pub fn parse_unit(text: &str) -> Result<Unit, String> {
    let cleaned = text.replace(['(', ')'], " ");
    let (num, den) = match cleaned.split_once('/') {
        Some((a, b)) => (a.to_string(), b.to_string()),
        None => (cleaned.clone(), String::new()),
    };
    if den.contains('/') {
        return Err(format!("unit `{text}` has more than one `/`"));
    }
    let mut dim = Dimension::default();
    let mut scale = 1.0;
    let mut atoms = 0usize;
    let mut kelvin = false;
    for (part, sign) in [(num, 1i8), (den, -1i8)] {
        for tok in part
            .split(|c: char| c == '*' || c == '·' || c.is_whitespace())
            .filter(|t| !t.is_empty())
        {
            let (base, exp) = match tok.split_once('^') {
                Some((b, e)) => (
                    b,
                    e.parse::<i8>()
                        .map_err(|_| format!("bad exponent in `{tok}`"))?,
                ),
                None => (tok, 1),
            };
            let (d, s) = atom(base).ok_or_else(|| format!("unknown unit `{base}`"))?;
            if base == "K" {
                kelvin = true;
            }
            let e = exp * sign;
            dim = dim.plus(d.scaled(e));
            scale *= s.powi(e as i32);
            atoms += 1;
        }
    }
    Ok(Unit {
        dimension: dim,
        scale,
        is_kelvin: kelvin && atoms == 1,
    })
}

/// Outcome of reading a quantity against a parameter's canonical unit.
#[derive(Debug, Clone, PartialEq)]
pub enum QuantityError {
    /// The text could not be parsed (reason).
    Parse(String),
    /// The unit parsed but its dimension differs from the canonical one.
    Dimension { given: String, expected: Dimension },
}

/// The number and the unit of a quantity's text (`"12.5 um"` → `("12.5", "um")`; the unit is
/// empty for a bare number).
pub fn split_quantity(text: &str) -> (&str, &str) {
    let text = text.trim();
    let split = text
        .char_indices()
        .find(|(i, c)| {
            !(c.is_ascii_digit()
                || *c == '.'
                || *c == '+'
                || *c == '-'
                || ((*c == 'e' || *c == 'E')
                    && *i > 0
                    && text[i + 1..]
                        .starts_with(|d: char| d.is_ascii_digit() || d == '-' || d == '+')))
        })
        .map(|(i, _)| i)
        .unwrap_or(text.len());
    let (num, unit) = text.split_at(split);
    (num.trim(), unit.trim())
}

/// Read `text` ("12 um", "1.2e-5 1/K", "20 degC", or a bare number meaning the canonical unit)
/// and return the value expressed in `canonical` (the parameter's unit string).
pub fn parse_quantity(text: &str, canonical: &str) -> Result<f64, QuantityError> {
    let (num, unit) = split_quantity(text);
    let value: f64 = num
        .trim()
        .parse()
        .map_err(|_| QuantityError::Parse(format!("`{num}` is not a number")))?;
    let unit = unit.trim();
    let target = parse_unit(canonical).map_err(QuantityError::Parse)?;
    if unit.is_empty() {
        return Ok(value);
    }
    let given = parse_unit(unit).map_err(QuantityError::Parse)?;
    if given.dimension != target.dimension {
        return Err(QuantityError::Dimension {
            given: unit.to_string(),
            expected: target.dimension,
        });
    }
    let canonical_is_absolute_celsius = canonical.trim() == "degC";
    if canonical_is_absolute_celsius && given.is_kelvin {
        return Ok(value - 273.15);
    }
    // Divide by the inverse of sub-unity ratios so "19 um" gives the same double as "19e-6".
    let ratio = given.scale / target.scale;
    Ok(if ratio < 1.0 {
        value / (1.0 / ratio).round_if_integral()
    } else {
        value * ratio
    })
}

/// Seconds of a duration written for people: `8h`, `90min`, `30s`, `1.5h`, `2h30min`,
/// `8 hours`, `250ms`, or a bare number of seconds. Each term is a quantity of this module
/// (`ms`, `s`, `min`, `h`, `d`, and the spelled-out `sec`, `minutes`, `hours`, `days`); several add
/// up. `m` is metres here as everywhere in the workspace, so `5m` is refused with a hint to write
/// `5min`. Must be > 0 and finite. The error says what is wrong, not which text (callers name it).
pub fn parse_duration(text: &str) -> Result<f64, String> {
    const EXAMPLES: &str = "examples: 8h, 90min, 30s";
    let s: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    if s.is_empty() {
        return Err(format!("empty; {EXAMPLES}"));
    }
    if let Ok(v) = s.parse::<f64>() {
        return positive_seconds(v);
    }
    let mut total = 0.0;
    let mut rest = s.as_str();
    while !rest.is_empty() {
        let num_len = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        if num_len == 0 {
            return Err(format!("expected a number at {rest:?}; {EXAMPLES}"));
        }
        let (num, after) = rest.split_at(num_len);
        let unit_len = after
            .find(|c: char| c.is_ascii_digit() || c == '.')
            .unwrap_or(after.len());
        let (unit, next) = after.split_at(unit_len);
        let atom = match unit {
            "" => {
                return Err(
                    "a number needs a unit when several terms are given (ms, s, min, h, d)".into(),
                )
            }
            "m" => {
                return Err(format!(
                    "`{num}m` is a length (m = metres): write {num}min for minutes"
                ))
            }
            "sec" | "secs" | "second" | "seconds" => "s",
            "mins" | "minute" | "minutes" => "min",
            "hr" | "hrs" | "hour" | "hours" => "h",
            "day" | "days" => "d",
            other => other,
        };
        total += parse_quantity(&format!("{num} {atom}"), "s").map_err(|e| match e {
            QuantityError::Parse(_) if !num.is_empty() && num.parse::<f64>().is_err() => {
                format!("{num:?} is not a number")
            }
            _ => format!("unknown time unit {unit:?} (use ms, s, min, h or d)"),
        })?;
        rest = next;
    }
    positive_seconds(total)
}

fn positive_seconds(v: f64) -> Result<f64, String> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err("must be > 0 and finite".into())
    }
}

trait RoundIfIntegral {
    fn round_if_integral(self) -> Self;
}

impl RoundIfIntegral for f64 {
    /// 1/1e-6 may come out as 999999.9999999999; snap such near-integers.
    fn round_if_integral(self) -> f64 {
        let r = self.round();
        if (self - r).abs() <= 1e-9 * r.abs() {
            r
        } else {
            self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_suffixed_values() {
        assert!((parse_quantity("12 um", "m").unwrap() - 12e-6).abs() < 1e-18);
        assert!((parse_quantity("1.2e-5 1/K", "1/K").unwrap() - 1.2e-5).abs() < 1e-18);
        assert!((parse_quantity("20 degC", "degC").unwrap() - 20.0).abs() < 1e-12);
        assert!((parse_quantity("293.15 K", "degC").unwrap() - 20.0).abs() < 1e-9);
        assert!((parse_quantity("0.8 um/m", "1").unwrap() - 0.8e-6).abs() < 1e-18);
        assert!((parse_quantity("30 min", "s").unwrap() - 1800.0).abs() < 1e-9);
        assert!((parse_quantity("99 kPa", "Pa").unwrap() - 99_000.0).abs() < 1e-6);
        assert!((parse_quantity("-3e-3", "m").unwrap() + 3e-3).abs() < 1e-18);
        assert!((parse_quantity("5 um/K", "m/K").unwrap() - 5e-6).abs() < 1e-18);
    }

    #[test]
    fn rejects_wrong_dimension() {
        match parse_quantity("5 mrad", "m") {
            Err(QuantityError::Dimension { given, .. }) => assert_eq!(given, "mrad"),
            other => panic!("expected dimension error, got {other:?}"),
        }
        assert!(matches!(
            parse_quantity("12 um", "1/K"),
            Err(QuantityError::Dimension { .. })
        ));
        assert!(matches!(
            parse_quantity("12 furlongs", "m"),
            Err(QuantityError::Parse(_))
        ));
        assert!(matches!(
            parse_quantity("abc", "m"),
            Err(QuantityError::Parse(_))
        ));
    }

    #[test]
    fn durations_parse_to_seconds_through_the_unit_table() {
        for (text, seconds) in [
            ("8h", 28_800.0),
            ("90min", 5_400.0),
            ("30s", 30.0),
            ("1.5h", 5_400.0),
            ("2h30min", 9_000.0),
            ("250ms", 0.25),
            ("45", 45.0),
            (" 3 min ", 180.0),
            ("8 hours", 28_800.0),
            ("2 days", 172_800.0),
            ("1d", 86_400.0),
        ] {
            assert_eq!(parse_duration(text).unwrap(), seconds, "{text}");
        }
    }

    #[test]
    fn minutes_are_min_and_m_is_refused_for_durations() {
        let e = parse_duration("5m").unwrap_err();
        assert!(e.contains("metres") && e.contains("5min"), "{e}");
        assert!(parse_duration("1h5m").is_err());
        for bad in ["", "8 fortnights", "h", "-5s", "0s", "1h30", "inf", "5 mm"] {
            assert!(parse_duration(bad).is_err(), "{bad}");
        }
        // the unit table itself: m is metres, cm a length, d a day
        assert_eq!(parse_quantity("5 m", "mm").unwrap(), 5000.0);
        assert_eq!(parse_quantity("2.5 cm", "m").unwrap(), 0.025);
        assert!(matches!(
            parse_quantity("5 m", "s"),
            Err(QuantityError::Dimension { .. })
        ));
    }
}
