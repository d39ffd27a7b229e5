//! Durations written as text on the command line and in node parameters: `8h`, `90min`, `30s`,
//! `1.5h`, `2h30min`, `8 hours`, or a bare number of seconds — parsed by the workspace's unit
//! table (`metrocell_physics::units::parse_duration`), where `m` is metres: minutes are `min`.

use crate::error::SimError;

/// Seconds of a duration text (see the module doc); the error names the text.
pub fn parse_duration(text: &str) -> Result<f64, SimError> {
    metrocell_physics::units::parse_duration(text)
        .map_err(|reason| SimError::invalid(format!("duration {text:?}"), reason))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documented_forms_parse_to_seconds() {
        assert_eq!(parse_duration("8h").unwrap(), 28_800.0);
        assert_eq!(parse_duration("90min").unwrap(), 5_400.0);
        assert_eq!(parse_duration("2h30min").unwrap(), 9_000.0);
        assert_eq!(parse_duration("45").unwrap(), 45.0);
    }

    #[test]
    fn nonsense_is_an_error_naming_the_text() {
        for bad in ["", "8 fortnights", "h", "-5s", "0s", "1h30", "inf", "5m"] {
            let e = parse_duration(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("{bad:?}")), "{bad}: {e}");
        }
        let e = parse_duration("30m").unwrap_err().to_string();
        assert!(e.contains("30min"), "{e}");
    }
}
