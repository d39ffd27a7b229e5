//! Coordinates written back into G-code.

/// `value` with `decimals` places, trailing zeros (and a trailing point) removed, no `-0`.
pub fn format_coordinate(value: f64, decimals: usize) -> String {
    let mut s = format!("{value:.decimals$}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" {
        s = "0".into();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trims_and_rounds() {
        assert_eq!(format_coordinate(100.08416, 4), "100.0842");
        assert_eq!(format_coordinate(98.216, 4), "98.216");
        assert_eq!(format_coordinate(-0.00001, 4), "0");
        assert_eq!(format_coordinate(12.0, 4), "12");
        assert_eq!(format_coordinate(-3.5, 5), "-3.5");
    }
}
