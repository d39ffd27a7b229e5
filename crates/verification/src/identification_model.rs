//! The model a plan is judged with when the user gives none: the errors one tracker target
//! (one SMR on the spindle) can identify on an XFYZ machine — each axis's positioning and its
//! two straightnesses as cubic series over the mesh's range, and the squareness of each pair
//! of axes that the mesh spans — with the tracker's pose identified alongside (P4/P5). With the
//! reflector at several tool offsets ([`multi_target_model_yaml`]) the roll, pitch and yaw of
//! each axis too: the same angle seen through Abbe arms of several lengths is what tells it
//! from a straightness (ISO 230-1 Annex A).

use nalgebra::Vector3;

use crate::Mesh;

/// [`single_target_model_yaml`] with the model's tool at `targets[0]` (m, from the spindle's
/// gauge point) and, when there are two or more targets, the nine angular errors of an XFYZ
/// machine as quadratic series (slope and bow of each angle) over the mesh's range, through the
/// P5 chain's Abbe arms: X's arm the tool point from the table's origin (levers x, y, z), Y's
/// the ram's extension and the tool (lever z), Z's the tool alone — each plus the tool offset.
pub fn multi_target_model_yaml(mesh: &Mesh, targets: &[Vector3<f64>]) -> String {
    let Some(tool) = targets.first() else {
        return single_target_model_yaml(mesh);
    };
    let mut text = model_yaml(mesh, Some(tool));
    if targets.len() < 2 {
        return text;
    }
    for (a, (axis, levers)) in [("x", "[x, y, z]"), ("y", "[z]"), ("z", "[]")]
        .iter()
        .enumerate()
    {
        if mesh.max[a] <= mesh.min[a] {
            continue;
        }
        let levels = ((mesh.max[a] - mesh.min[a]) / mesh.step).round() as usize + 1;
        let order = (levels - 1).min(2);
        let params: Vec<String> = (0..=order).map(|k| format!("c{k}: 0 urad")).collect();
        let travel = format!("[{} mm, {} mm]", mesh.min[a] * 1e3, mesh.max[a] * 1e3);
        for about in ["x", "y", "z"] {
            text += &format!(
                "  - {{id: angular, options: {{axis: {axis}, about: {about}, lever_axes: {levers}, abbe_offset: {}, order: {order}, travel: {travel}}}, params: {{{}}}}}\n",
                mm(tool),
                params.join(", ")
            );
        }
    }
    text
}

/// The cell file text (the twin's format) of that model, tracker pose at the origin. Each
/// series is cubic, or of the order the mesh's levels on its axis can carry (3 levels: a
/// quadratic), so no term is declared that the plan could not identify.
pub fn single_target_model_yaml(mesh: &Mesh) -> String {
    model_yaml(mesh, None)
}

/// A vector as the cell file writes it, mm.
fn mm(v: &Vector3<f64>) -> String {
    format!("[{} mm, {} mm, {} mm]", v.x * 1e3, v.y * 1e3, v.z * 1e3)
}

/// [`single_target_model_yaml`]'s text, the model's tool at `tool` (m) when given.
fn model_yaml(mesh: &Mesh, tool: Option<&Vector3<f64>>) -> String {
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
    let tool = tool.map_or(String::new(), |t| format!("  tool_offset: {}\n", mm(t)));
    format!(
        "name: verification_plan\nmachine:\n  family: cartesian\n  stacking: XFYZ\n  travel: {{x: {}, y: {}, z: {}}}\n{tool}sensors:\n  tracker:\n    pose: {{translation: [0 mm, 0 mm, 0 mm], euler_xyz: [0 deg, 0 deg, 0 deg]}}\nterms:\n{terms}",
        travel(0),
        travel(1),
        travel(2)
    )
}
