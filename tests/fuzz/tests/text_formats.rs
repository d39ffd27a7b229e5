//! The text formats a user writes or another program exports: the cell file, camera_info YAML,
//! a launch file's YAML, URDF, `.msg` definitions, G-code (blocks, and whole programs through
//! the compensator), and Marlin's M503 reply. Each harness starts from a shipped example (or
//! the format's tokens) and checks the parser returns, whatever it returns.

use bolero::check;
use metrocell_fuzz::limits::{bounded, report};
use metrocell_fuzz::{bytes, from_alphabet, mutate, workspace_root};

fn seed(path: &str) -> Vec<u8> {
    std::fs::read(workspace_root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[test]
fn cell_files() {
    let seeds = [
        seed("crates/twin/examples/cells/quick_demo.yaml"),
        seed("crates/twin/examples/cells/five_axis_table.yaml"),
        seed("crates/twin/examples/cells/serial_arm_ur5.yaml"),
        seed("crates/twin/examples/cells/delta_printer.yaml"),
    ];
    let dir = workspace_root().join("crates/twin/examples/cells");
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("cell_files", input, || {
                let s = &seeds[input.first().map_or(0, |b| usize::from(*b) % seeds.len())];
                let text = String::from_utf8_lossy(&mutate(s, input)).into_owned();
                let _ = metrocell_model_file::CellModel::from_yaml_str_in(&text, "fuzz.yaml", &dir);
            })
        });
    println!("{}", report("cell_files"));
}

#[test]
fn camera_info_yaml() {
    let s = b"image_width: 640\nimage_height: 480\ncamera_name: c\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [500, 0, 319.5, 0, 500, 239.5, 0, 0, 1]\ndistortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [-0.1, 0.01, 0, 0, 0]\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\nprojection_matrix:\n  rows: 3\n  cols: 4\n  data: [500, 0, 319.5, 0, 0, 500, 239.5, 0, 0, 0, 1, 0]\n";
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("camera_info_yaml", input, || {
                let text = String::from_utf8_lossy(&mutate(s, input)).into_owned();
                if let Ok(info) = metrocell_camera_model::CameraInfo::from_yaml(&text, "fuzz") {
                    let _ = info.to_model();
                    let _ = info.intrinsics_covariance();
                }
            })
        });
    println!("{}", report("camera_info_yaml"));
}

#[test]
fn launch_yaml() {
    let s = seed("launch-configs/demo.launch.yaml");
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("launch_yaml", input, || {
                let text = String::from_utf8_lossy(&mutate(&s, input)).into_owned();
                let _ = metrocell_launch::marked_yaml::parse_marked_yaml(&text);
            })
        });
    println!("{}", report("launch_yaml"));
}

#[test]
fn launch_plans() {
    // the whole loader on a file: substitutions, arguments, conditions, parameter files
    let s = seed("launch-configs/demo.launch.yaml");
    let dir = std::env::temp_dir().join(format!("metrocell-fuzz-launch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("fuzz.launch.yaml");
    let options = metrocell_launch::options::LaunchOptions {
        share_dir: Some(workspace_root()),
        executable_search_path: Some(vec![dir.clone()]),
        environment: Some(Default::default()),
        ..Default::default()
    };
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("launch_plans", input, || {
                std::fs::write(&file, mutate(&s, input)).unwrap();
                let _ = metrocell_launch::load_launch_plan(&file, &[], &options);
            })
        });
    println!("{}", report("launch_plans"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn urdf() {
    let s = seed("crates/twin/examples/cells/mobile_manipulator.urdf");
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("urdf", input, || {
                let text = String::from_utf8_lossy(&mutate(&s, input)).into_owned();
                let _ = metrocell_kinematics::urdf_chain::chain_from_urdf_str(
                    &text,
                    "base_link",
                    "prism",
                );
            })
        });
    println!("{}", report("urdf"));
}

#[test]
fn msg_definitions() {
    let s = seed("msgs/interfaces/sensor_msgs/msg/CameraInfo.msg");
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("msg_definitions", input, || {
                let text = String::from_utf8_lossy(&mutate(&s, input)).into_owned();
                let _ = rosmsg::parse::parse_message("fuzz_msgs", "Fuzz", &text);
            })
        });
    println!("{}", report("msg_definitions"));
}

const GCODE: &[&str] = &[
    "G0", "G1", "G2", "G3", "G17", "G18", "G19", "G20", "G21", "G90", "G91", " X", " Y", " Z",
    " I", " J", " K", " R", " F", "1", "0", "-", ".", "5", "9", "e", "(", ")", ";", "\n", " ",
    "N10", "M3", "S", "%",
];

#[test]
fn gcode_programs() {
    let field = metrocell_gcode::planar_quadratic::PlanarQuadraticField {
        coefficients: [1e-5, 5e-3, -7e-3, 5e-3, 1e-2, 1e-2, -1e-5, -2e-5, -1.5e-5],
        x3: 1.0,
        region: None,
    };
    let options = metrocell_gcode::CompensationOptions::default();
    check!()
        .with_generator(bytes(1024))
        .for_each(|input: &Vec<u8>| {
            bounded("gcode_programs", input, || {
                let text = from_alphabet(input, GCODE);
                for line in text.lines() {
                    let _ = metrocell_gcode::block::parse_block(line);
                }
                let _ = metrocell_gcode::compensate_program(&text, &field, &options);
            })
        });
    println!("{}", report("gcode_programs"));
}

#[test]
fn marlin_settings() {
    let s = b"echo:  M665 L215.00 R105.60 H250.00 S200.00 X0.20 Y-0.10 Z0.00 A0 B0 C0\necho:  M666 X-0.40 Y0.00 Z-0.10\n";
    check!()
        .with_generator(bytes(256))
        .for_each(|input: &Vec<u8>| {
            bounded("marlin_settings", input, || {
                let text = String::from_utf8_lossy(&mutate(s, input)).into_owned();
                if let Ok(m) = metrocell_kinematics::delta_firmware::MarlinDelta::from_gcode(&text)
                {
                    if let Ok(g) = m.firmware_geometry() {
                        let _ = m.corrected(&g);
                    }
                    let _ = m.klipper_sections();
                }
            })
        });
    println!("{}", report("marlin_settings"));
}
