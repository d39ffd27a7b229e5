//! Helpers shared by the metrocell-msgs tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A registry parsed from the `.msg` files on disk (not the texts embedded in the crate).
pub fn registry_from_files() -> rosmsg::Registry {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut r = rosmsg::Registry::new();
    r.add_package_dir("metrocell_msgs", &root.join("msg"))
        .unwrap();
    r.add_tree(&root.join("interfaces")).unwrap();
    r.check().unwrap();
    r
}

/// The Python interpreter for reference peers: `METROCELL_PYTHON`, else `<workspace>/.venv/bin/python`.
pub fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv/bin/python");
    if venv.exists() {
        return venv;
    }
    panic!(
        "no Python for the reference peers: set METROCELL_PYTHON or run `tests/run` (it creates {})",
        venv.display()
    );
}
