//! Generates the Rust message types from the `.msg` files: `msg/` (this package's own types,
//! package `metrocell_msgs`) and `interfaces/<pkg>/msg/` (standard ROS 2 types, vendored).

use std::path::Path;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    println!("cargo:rerun-if-changed=msg");
    println!("cargo:rerun-if-changed=interfaces");
    let mut registry = rosmsg::Registry::new();
    if let Err(e) = registry.add_package_dir("metrocell_msgs", &root.join("msg")) {
        panic!("metrocell_msgs: {e}");
    }
    if let Err(e) = registry.add_tree(&root.join("interfaces")) {
        panic!("metrocell_msgs interfaces: {e}");
    }
    let code = match rosmsg::codegen::generate_rust(&registry, "metrocell_msgs") {
        Ok(code) => code,
        Err(e) => panic!("metrocell_msgs: {e}"),
    };
    let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR set by cargo"))
        .join("metrocell_msgs.rs");
    std::fs::write(&out, code).unwrap_or_else(|e| panic!("writing {}: {e}", out.display()));
}
