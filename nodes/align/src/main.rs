//! `metrocell-align`: seed 003's frame alignment as a node (see the library's docs).
//!
//!   metrocell-align --ros-args -p action:=/ur5/move_tool -p urdf:=camera_joint.urdf \
//!       -p cell_pose:=camera_mount.yaml -p keep_publishing:=true

use metrocell_node::MetrocellNode;

fn main() -> std::process::ExitCode {
    let (mut node, _) =
        match MetrocellNode::from_env_args("align", metrocell_align_node::declarations()) {
            Ok(n) => n,
            Err(e) => {
                eprintln!("metrocell-align: {e}");
                return std::process::ExitCode::FAILURE;
            }
        };
    match metrocell_align_node::run(&mut node) {
        Ok(Some(_)) => std::process::ExitCode::SUCCESS,
        Ok(None) => {
            node.warn("shut down before the alignment finished: nothing written");
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            node.error(&e);
            eprintln!("metrocell-align: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
