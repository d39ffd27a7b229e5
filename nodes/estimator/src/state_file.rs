//! The last published state, kept in a file so a restarted node goes on from it instead of from
//! the model file's start values. (Its own latched topic cannot serve: a transient-local sample
//! lives only as long as its writer, which died with the previous process.)
//!
//! Format: JSON `{parameter_names, values, free, covariance, stamp_ns}` — the stacked parameter
//! vector, the names of the free parameters and their covariance (row-major, free order). Written
//! to a temporary file then renamed, so a crash never leaves half a file.

use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedState {
    pub parameter_names: Vec<String>,
    pub values: Vec<f64>,
    pub free: Vec<String>,
    pub covariance: Vec<f64>,
    pub stamp_ns: i64,
}

impl SavedState {
    /// Write atomically (temporary file + rename).
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let tmp = path.with_extension("tmp");
        std::fs::write(
            &tmp,
            serde_json::to_vec(self).map_err(std::io::Error::other)?,
        )?;
        std::fs::rename(&tmp, path)
    }

    /// Read `path`; None when it does not exist. Errors name the file.
    pub fn load(path: &Path) -> Result<Option<SavedState>, String> {
        let text = match std::fs::read(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(format!("state file {}: {e}", path.display())),
        };
        serde_json::from_slice(&text).map(Some).map_err(|e| format!("state file {}: not a saved estimator state ({e}); delete it to start from the model file", path.display()))
    }

    /// The start vector and free covariance for a model with these parameter names and free
    /// set, or why the saved state does not fit it.
    pub fn start_for(
        &self,
        names: &[String],
        free: &[usize],
    ) -> Result<(Vec<f64>, DMatrix<f64>), String> {
        if self.parameter_names != names {
            return Err("its parameters are not the model's (the model file changed)".into());
        }
        let free_names: Vec<String> = free.iter().map(|&k| names[k].clone()).collect();
        if self.free != free_names {
            return Err("its free parameters are not the model's".into());
        }
        let k = free.len();
        if self.values.len() != names.len()
            || self.covariance.len() != k * k
            || !self
                .values
                .iter()
                .chain(&self.covariance)
                .all(|v| v.is_finite())
        {
            return Err("its values or covariance have the wrong length or are not finite".into());
        }
        Ok((
            self.values.clone(),
            DMatrix::from_row_slice(k, k, &self.covariance),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_mismatches_are_named() {
        let dir = std::env::temp_dir().join(format!("estimator-state-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("state.json");
        let _ = std::fs::remove_file(&path);
        assert_eq!(SavedState::load(&path).unwrap(), None);
        let names = vec!["a.c0".to_string(), "a.c1".to_string()];
        let s = SavedState {
            parameter_names: names.clone(),
            values: vec![1e-6, 2e-6],
            free: vec!["a.c1".into()],
            covariance: vec![4e-12],
            stamp_ns: 7,
        };
        s.save(&path).unwrap();
        let back = SavedState::load(&path).unwrap().unwrap();
        assert_eq!(back, s);
        let (x, p) = back.start_for(&names, &[1]).unwrap();
        assert_eq!((x, p[(0, 0)]), (vec![1e-6, 2e-6], 4e-12));
        assert!(back
            .start_for(&names, &[0])
            .unwrap_err()
            .contains("free parameters"));
        assert!(back
            .start_for(&["b.c0".into(), "a.c1".into()], &[1])
            .unwrap_err()
            .contains("model file changed"));
        std::fs::write(&path, "not json").unwrap();
        assert!(SavedState::load(&path).unwrap_err().contains("state.json"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
