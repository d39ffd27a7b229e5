//! The model a plan is judged with when the user gives none: the errors one tracker target
//! (one SMR on the spindle) can identify on an XFYZ machine — each axis's positioning and its
//! two straightnesses as cubic series over the mesh's range, and the squareness of each pair
//! of axes that the mesh spans — with the tracker's pose identified alongside (P4/P5). Angular
//! errors need targets at several tool offsets (their Abbe arm): give a model that declares
//! them, and the tool offsets, with `--model`.

use crate::Mesh;

/// The cell file text (the twin's format) of that model, tracker pose at the origin. Each
/// series is cubic, or of the order the mesh's levels on its axis can carry (3 levels: a
/// quadratic), so no term is declared that the plan could not identify.
pub fn single_target_model_yaml(mesh: &Mesh) -> String {
    let axes = ['x', 'y', 'z'];
    let spans: Vec<bool> = (0..3).map(|a| mesh.max[a] > mesh.min[a]).collect();
    let travel = |a: usize| {
        let hi = if spans[a] {
            mesh.max[a]
        } else {
            mesh.min[a] + mesh.step
        };
        format!("[{} mm, {} mm]", mesh.min[a] * 1e3, hi * 1e3)
    };
    let mut terms = String::new();
    for (a, &axis) in axes.iter().enumerate().filter(|(a, _)| spans[*a]) {
        let t = travel(a);
        let levels = ((mesh.max[a] - mesh.min[a]) / mesh.step).round() as usize + 1;
        let order = (levels - 1).min(3);
        let params: Vec<String> = (0..=order).map(|k| format!("c{k}: 0 um")).collect();
        let params = params.join(", ");
        terms += &format!("  - {{id: positioning, options: {{axis: {axis}, order: {order}, travel: {t}}}, params: {{{params}}}}}\n");
        for d in axes.iter().filter(|d| **d != axis) {
            terms += &format!("  - {{id: straightness, options: {{axis: {axis}, direction: {d}, order: {order}, travel: {t}}}, params: {{{params}}}}}\n");
        }
    }
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if spans[i] && spans[j] {
            terms += &format!(
                "  - {{id: squareness, options: {{pair: {}{}}}, params: {{s: 0 urad}}}}\n",
                axes[i], axes[j]
            );
        }
    }
    format!(
        "name: verification_plan\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {{x: {}, y: {}, z: {}}}\nsensors:\n  tracker:\n    pose: {{translation: [0 mm, 0 mm, 0 mm], euler_xyz: [0 deg, 0 deg, 0 deg]}}\nterms:\n{terms}",
        travel(0),
        travel(1),
        travel(2)
    )
}
