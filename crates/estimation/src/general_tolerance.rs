//! General tolerances for linear dimensions, ISO 2768-1:1989 Table 1: the permissible deviation
//! (± mm) of a dimension without an individual tolerance, by tolerance class (f fine, m medium,
//! c coarse, v very coarse) and nominal size range.
//!
//! Seed 000 judges its router "ISO 2768-c" before and after compensation; the paper names the
//! class but not its values (its digest, §6.9, takes them from the standard). Ranges are closed
//! above: 30 mm falls in "over 6 up to 30". Below 0.5 mm the standard gives no general tolerance
//! (it must be indicated next to the dimension), and class f has none over 2000 mm nor class v
//! up to 3 mm: those are errors here, never a silent default.

use std::fmt;

/// ISO 2768-1 tolerance class for linear dimensions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ToleranceClass {
    Fine,
    Medium,
    Coarse,
    VeryCoarse,
}

impl ToleranceClass {
    /// Finest first.
    pub const ALL: [ToleranceClass; 4] = [Self::Fine, Self::Medium, Self::Coarse, Self::VeryCoarse];

    /// The class's letter as drawings write it ("ISO 2768-c").
    pub fn letter(self) -> char {
        match self {
            Self::Fine => 'f',
            Self::Medium => 'm',
            Self::Coarse => 'c',
            Self::VeryCoarse => 'v',
        }
    }

    /// The class for a drawing's letter (f, m, c, v; either case).
    pub fn from_letter(letter: char) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|c| c.letter() == letter.to_ascii_lowercase())
    }
}

impl fmt::Display for ToleranceClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ISO 2768-{}", self.letter())
    }
}

/// Upper ends of the size ranges (mm); the first range starts at 0.5 mm.
const RANGE_UPPER_MM: [f64; 8] = [3.0, 6.0, 30.0, 120.0, 400.0, 1000.0, 2000.0, 4000.0];

/// Permissible deviations (± mm) per range, in [`ToleranceClass::ALL`]'s order; NaN = not given.
const DEVIATION_MM: [[f64; 8]; 4] = [
    [0.05, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5, f64::NAN],
    [0.1, 0.1, 0.2, 0.3, 0.5, 0.8, 1.2, 2.0],
    [0.2, 0.3, 0.5, 0.8, 1.2, 2.0, 3.0, 4.0],
    [f64::NAN, 0.5, 1.0, 1.5, 2.5, 4.0, 6.0, 8.0],
];

/// Why a size has no general tolerance.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ToleranceError {
    #[error(
        "{size_mm} mm is below 0.5 mm: ISO 2768-1 gives no general tolerance there; \
         state the tolerance next to the dimension"
    )]
    BelowRange { size_mm: f64 },
    #[error("{size_mm} mm is above 4000 mm, the largest size ISO 2768-1 covers")]
    AboveRange { size_mm: f64 },
    #[error("{class} gives no tolerance for {size_mm} mm; use a coarser or finer class")]
    NotInClass { class: ToleranceClass, size_mm: f64 },
    #[error("the size must be a finite number of millimetres, got {size_mm}")]
    NotFinite { size_mm: f64 },
}

/// The permissible deviation (± mm) of a nominal size `size_mm` in `class`.
pub fn permissible_deviation_mm(
    class: ToleranceClass,
    size_mm: f64,
) -> Result<f64, ToleranceError> {
    if !size_mm.is_finite() {
        return Err(ToleranceError::NotFinite { size_mm });
    }
    if size_mm < 0.5 {
        return Err(ToleranceError::BelowRange { size_mm });
    }
    let range = RANGE_UPPER_MM
        .iter()
        .position(|&upper| size_mm <= upper)
        .ok_or(ToleranceError::AboveRange { size_mm })?;
    let d = DEVIATION_MM[class as usize][range];
    if d.is_nan() {
        return Err(ToleranceError::NotInClass { class, size_mm });
    }
    Ok(d)
}

/// The finest class whose tolerance at `size_mm` covers a deviation of `deviation_mm` (its
/// magnitude); `Ok(None)` when even class v does not.
pub fn finest_class_met(
    size_mm: f64,
    deviation_mm: f64,
) -> Result<Option<ToleranceClass>, ToleranceError> {
    if !deviation_mm.is_finite() {
        return Err(ToleranceError::NotFinite {
            size_mm: deviation_mm,
        });
    }
    let mut any_class = false;
    for class in ToleranceClass::ALL {
        match permissible_deviation_mm(class, size_mm) {
            Ok(d) => {
                any_class = true;
                if deviation_mm.abs() <= d {
                    return Ok(Some(class));
                }
            }
            Err(ToleranceError::NotInClass { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    debug_assert!(any_class, "every range has at least one class");
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_ends_belong_to_the_lower_range() {
        let c = ToleranceClass::Coarse;
        assert_eq!(permissible_deviation_mm(c, 30.0), Ok(0.5));
        assert_eq!(permissible_deviation_mm(c, 30.000001), Ok(0.8));
        assert_eq!(permissible_deviation_mm(c, 0.5), Ok(0.2));
        assert_eq!(permissible_deviation_mm(c, 4000.0), Ok(4.0));
    }

    #[test]
    fn gaps_of_the_table_are_errors() {
        assert!(matches!(
            permissible_deviation_mm(ToleranceClass::Fine, 3000.0),
            Err(ToleranceError::NotInClass { .. })
        ));
        assert!(matches!(
            permissible_deviation_mm(ToleranceClass::VeryCoarse, 2.0),
            Err(ToleranceError::NotInClass { .. })
        ));
        assert!(matches!(
            permissible_deviation_mm(ToleranceClass::Medium, 4001.0),
            Err(ToleranceError::AboveRange { .. })
        ));
        assert!(matches!(
            permissible_deviation_mm(ToleranceClass::Medium, f64::NAN),
            Err(ToleranceError::NotFinite { .. })
        ));
    }

    #[test]
    fn finest_class_met_walks_from_fine_to_very_coarse() {
        assert_eq!(finest_class_met(100.0, 0.1), Ok(Some(ToleranceClass::Fine)));
        assert_eq!(
            finest_class_met(100.0, -0.3),
            Ok(Some(ToleranceClass::Medium))
        );
        assert_eq!(
            finest_class_met(100.0, 0.31),
            Ok(Some(ToleranceClass::Coarse))
        );
        assert_eq!(
            finest_class_met(100.0, 1.5),
            Ok(Some(ToleranceClass::VeryCoarse))
        );
        assert_eq!(finest_class_met(100.0, 1.51), Ok(None));
        // over 2000 mm class f has no value: the walk starts at m
        assert_eq!(
            finest_class_met(3000.0, 0.1),
            Ok(Some(ToleranceClass::Medium))
        );
        assert_eq!(
            ToleranceClass::from_letter('C'),
            Some(ToleranceClass::Coarse)
        );
        assert_eq!(ToleranceClass::Coarse.to_string(), "ISO 2768-c");
    }
}
