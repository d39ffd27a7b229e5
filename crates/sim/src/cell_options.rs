//! What a run may change of a cell file without editing it: the ground's tilt under a stationing
//! program's robot (`metrocell sim --ground-tilt ROLL,PITCH`, the node's `ground_tilt`
//! parameter: one cell, a recording per ground), and the run's duration when none is given (a
//! stationing program's one pass).

use std::path::Path;

use metrocell_twin::quantity::Quantity;
use metrocell_twin::stationing::check_tilt;
use metrocell_twin::Cell;

use crate::error::SimError;

/// `ROLL,PITCH`, each a number in rad or a text with an angle unit (`0,15mrad`,
/// `"2 mrad, -1.5 mrad"`, `0.5deg,0`).
pub fn parse_ground_tilt(text: &str) -> Result<[f64; 2], SimError> {
    let what = "--ground-tilt";
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 2 || parts.iter().any(|p| p.is_empty()) {
        return Err(SimError::invalid(what, format!("`{text}` is not ROLL,PITCH (e.g. 0,15mrad: roll about the base's x, then pitch about its y)")));
    }
    let mut out = [0.0; 2];
    for (v, p) in out.iter_mut().zip(&parts) {
        let q = match p.parse::<f64>() {
            Ok(n) => Quantity::Number(n),
            Err(_) => Quantity::Text(p.to_string()),
        };
        *v = q
            .to_si(what, "rad")
            .map_err(|e| SimError::invalid(what, e.to_string()))?;
    }
    check_tilt(out, what).map_err(|e| SimError::invalid(what, e.to_string()))?;
    Ok(out)
}

/// The cell of `path` with, when given, the ground's tilt replaced (its stationing program's
/// `environment.ground_tilt`); a tilt for a cell without a stationing program is refused.
pub fn load_cell(path: &Path, ground_tilt: Option<[f64; 2]>) -> Result<Cell, SimError> {
    let mut cell = Cell::from_path(path)?;
    if let Some(tilt) = ground_tilt {
        let st = cell.stationing.as_mut().ok_or_else(|| SimError::invalid("--ground-tilt", format!("{} has no stationing program (`program.stationing`): the ground's tilt is simulated for a robot measured by a levelled instrument only", path.display())))?;
        st.ground_tilt = tilt;
    }
    Ok(cell)
}

/// The run's duration: the one given, else the cell's natural one (a stationing program's pass).
pub fn run_duration(cell: &Cell, given: Option<f64>, path: &Path) -> Result<f64, SimError> {
    given.or_else(|| cell.natural_duration()).ok_or_else(|| SimError::invalid("--duration", format!("is required: {} runs its program through a shift of the length you choose (e.g. --duration 8h); only a stationing program has a length of its own", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_tilts_parse_with_units_and_bad_ones_say_the_form() {
        assert_eq!(parse_ground_tilt("0,15mrad").unwrap(), [0.0, 0.015]);
        let t = parse_ground_tilt(" 2 mrad , -0.5 deg").unwrap();
        assert!(
            (t[0] - 0.002).abs() < 1e-15 && (t[1] + 0.5f64.to_radians()).abs() < 1e-15,
            "{t:?}"
        );
        assert_eq!(parse_ground_tilt("0.01,0").unwrap(), [0.01, 0.0]);
        for bad in ["15mrad", "1,2,3", "0,15 mm", "0,30 deg", ","] {
            let e = parse_ground_tilt(bad).unwrap_err().to_string();
            assert!(e.starts_with("--ground-tilt"), "{bad}: {e}");
        }
        assert!(parse_ground_tilt("15mrad")
            .unwrap_err()
            .to_string()
            .contains("ROLL,PITCH"));
        assert!(parse_ground_tilt("0,30 deg")
            .unwrap_err()
            .to_string()
            .contains("±0.2 rad"));
    }
}
