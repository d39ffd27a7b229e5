//! Seed 004 fixture K3: the DH table as the paper printed it (its a and α columns swapped: a₂ =
//! 90, α₂ = d₁) must not load as a machine. Each way it can be written is refused with the row,
//! the column and what to write instead; the reconstructed table loads.

use std::path::Path;

use metrocell_model_file::CellModel;

fn arm(rows: &str) -> Result<CellModel, String> {
    let text = format!(
        "name: k3\nmachine:\n  family: serial_arm\n  serial_arm:\n    dh:\n      convention: standard\n      rows:\n{rows}"
    );
    CellModel::from_yaml_str_in(&text, "k3.yaml", Path::new(".")).map_err(|e| e.to_string())
}

#[test]
fn the_printed_table_is_refused_and_the_reconstructed_one_loads() {
    // a₂ = 90 as a bare number: 90 m
    let e = arm("        - {theta: 90 deg, d: 0.228, joint: prismatic}\n        - {theta: 0 deg, a: 90, alpha: 0}\n")
        .unwrap_err();
    assert!(
        e.contains("rows[1].a") && e.contains("90 m") && e.contains("`90 deg`"),
        "{e}"
    );
    // a₂ = 90°: an angle in a length column
    let e = arm("        - {theta: 90 deg, d: 0.228, joint: prismatic}\n        - {a: 90 deg}\n")
        .unwrap_err();
    assert!(e.contains("rows[1].a"), "{e}");
    // α₂ = d₁: a symbol where a number belongs
    let e = arm("        - {theta: 90 deg, d: 0.228, joint: prismatic}\n        - {alpha: d_1}\n")
        .unwrap_err();
    assert!(e.contains("rows[1].alpha") && e.contains("d_1"), "{e}");
    // the digest's reconstruction (K1's table): α = 90°, −90°, lengths in mm
    arm("        - {theta: 90 deg, d: 228 mm, alpha: 90 deg, joint: prismatic}\n        - {theta: 0 deg, d: 308 mm, alpha: -90 deg, joint: prismatic}\n")
        .unwrap();
}
