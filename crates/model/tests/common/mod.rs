//! What the forward-model tests share.

use metrocell_physics::{configure, ConfiguredTerm, TermConfig};

/// A catalog term from its cell-file YAML (`id`, `options`, `params`).
pub fn term(yaml: &str) -> ConfiguredTerm {
    let c: TermConfig = serde_yaml::from_str(yaml).unwrap();
    configure(&c).unwrap_or_else(|e| panic!("{yaml}: {e}"))
}
