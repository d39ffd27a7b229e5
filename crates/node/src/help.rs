//! `NODE --help`: what a node takes, printed before anything else happens — in particular before
//! a DDS participant exists, so asking a node for help never puts it on the network.

use crate::params::ParamDecl;

/// True when the node's own arguments (argv[0] excluded, before `--ros-args`) ask for help.
pub fn asks_for_help(node_args: &[String]) -> bool {
    node_args.iter().any(|a| a == "--help" || a == "-h")
}

/// The help text: usage line, the node's own arguments (if any), every declared parameter with
/// its type, default, range or allowed values and description, and the ROS 2 arguments.
pub fn help_text(
    program: &str,
    node_name: &str,
    own_arguments: &[(String, String)],
    decls: &[ParamDecl],
) -> String {
    let mut s = String::new();
    let own = if own_arguments.is_empty() {
        String::new()
    } else {
        " [NODE ARGUMENTS]".to_string()
    };
    s.push_str(&format!("metrocell node `{node_name}`\n\nUsage: {program}{own} [--ros-args -p NAME:=VALUE ... --params-file FILE -r FROM:=TO ...]\n"));
    if !own_arguments.is_empty() {
        s.push_str("\nNode arguments (before --ros-args):\n");
        for (flag, what) in own_arguments {
            s.push_str(&format!("  {flag}\n      {what}\n"));
        }
    }
    s.push_str("\nParameters (-p NAME:=VALUE, or in a --params-file under the node's name):\n");
    for d in decls {
        let mut rule = String::new();
        if let Some((lo, hi)) = d.range {
            rule = format!(", range [{lo}, {hi}]");
        }
        if let Some(allowed) = &d.allowed {
            rule = format!(
                ", one of {}",
                allowed
                    .iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(" | ")
            );
        }
        s.push_str(&format!(
            "  {} ({}, default {}{rule})\n      {}\n",
            d.name,
            d.param_type(),
            d.default,
            d.description
        ));
    }
    s.push_str(
        "\nROS 2 arguments: -r __node:=NAME, -r __ns:=/NAMESPACE, -r TOPIC:=NEW_TOPIC, --log-level LEVEL.\n\
         Environment: ROS_DOMAIN_ID (0..232); ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or ROS_LOCALHOST_ONLY=1\n\
         keeps the node's DDS traffic on 127.0.0.1; METROCELL_DDS_LOG=LEVEL (error..trace) prints what DDS\n\
         itself reports (participants lost and found, socket errors) on stderr.\n",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn help_lists_parameters_with_rules_and_node_arguments() {
        let decls = vec![
            ParamDecl::new("rate", 10.0, "publish rate (Hz)").with_range(0.1, 100.0),
            ParamDecl::new("mode", "fast".to_string(), "how to run")
                .with_allowed(["fast", "exact"]),
        ];
        let own = vec![("--bag IN_BAG".to_string(), "run on a bag".to_string())];
        let text = help_text("metrocell-x", "x", &own, &decls);
        assert!(text.contains("rate (double, default 10"), "{text}");
        assert!(text.contains("range [0.1, 100]"), "{text}");
        assert!(text.contains("one of \"fast\" | \"exact\""), "{text}");
        assert!(
            text.contains("--bag IN_BAG") && text.contains("[NODE ARGUMENTS]"),
            "{text}"
        );
        assert!(asks_for_help(&["--help".to_string()]) && asks_for_help(&["-h".to_string()]));
        assert!(!asks_for_help(&["--bag".to_string(), "x".to_string()]));
    }
}
