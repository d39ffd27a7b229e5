//! Durations written as text on the command line: `8h`, `90min`, `30s`, `1.5h`, `2h30min`,
//! `8 hours`, or a bare number of seconds.

use crate::error::SimError;

/// Seconds of a duration text. Units: `ms`, `s`/`sec`/`seconds`, `min`/`m`/`minutes`,
/// `h`/`hr`/`hours`, `d`/`days`; several
/// terms add up (`1h30min`). A bare number is seconds. Must be > 0 and finite.
pub fn parse_duration(text: &str) -> Result<f64, SimError> {
    let what = format!("duration {text:?}");
    let s: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    if s.is_empty() {
        return Err(SimError::invalid(what, "empty; examples: 8h, 90min, 30s"));
    }
    if let Ok(v) = s.parse::<f64>() {
        return positive(v, &what);
    }
    let mut total = 0.0;
    let mut rest = s.as_str();
    while !rest.is_empty() {
        let num_len = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        if num_len == 0 {
            return Err(SimError::invalid(
                &what,
                format!("expected a number at {rest:?}; examples: 8h, 90min, 30s"),
            ));
        }
        let value: f64 = rest[..num_len].parse().map_err(|_| {
            SimError::invalid(&what, format!("{:?} is not a number", &rest[..num_len]))
        })?;
        rest = &rest[num_len..];
        let unit_len = rest
            .find(|c: char| c.is_ascii_digit() || c == '.')
            .unwrap_or(rest.len());
        let unit = &rest[..unit_len];
        let scale = match unit {
            "ms" => 1e-3,
            "s" | "sec" | "secs" | "second" | "seconds" => 1.0,
            "m" | "min" | "mins" | "minute" | "minutes" => 60.0,
            "h" | "hr" | "hrs" | "hour" | "hours" => 3600.0,
            "d" | "day" | "days" => 86_400.0,
            "" => {
                return Err(SimError::invalid(
                    &what,
                    "a number needs a unit when several terms are given (ms, s, min, h, d)",
                ))
            }
            other => {
                return Err(SimError::invalid(
                    &what,
                    format!("unknown unit {other:?} (use ms, s, min, h or d)"),
                ))
            }
        };
        total += value * scale;
        rest = &rest[unit_len..];
    }
    positive(total, &what)
}

fn positive(v: f64, what: &str) -> Result<f64, SimError> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(SimError::invalid(what, "must be > 0 and finite"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documented_forms_parse_to_seconds() {
        assert_eq!(parse_duration("8h").unwrap(), 28_800.0);
        assert_eq!(parse_duration("90min").unwrap(), 5_400.0);
        assert_eq!(parse_duration("30s").unwrap(), 30.0);
        assert_eq!(parse_duration("1.5h").unwrap(), 5_400.0);
        assert_eq!(parse_duration("2h30min").unwrap(), 9_000.0);
        assert_eq!(parse_duration("250ms").unwrap(), 0.25);
        assert_eq!(parse_duration("45").unwrap(), 45.0);
        assert_eq!(parse_duration(" 3 min ").unwrap(), 180.0);
        assert_eq!(parse_duration("8 hours").unwrap(), 28_800.0);
    }

    #[test]
    fn nonsense_is_an_error_naming_the_text() {
        for bad in ["", "8 fortnights", "h", "-5s", "0s", "1h30", "inf"] {
            let e = parse_duration(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("{bad:?}")), "{bad}: {e}");
        }
    }
}
