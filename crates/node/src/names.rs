//! ROS 2 names (design.ros2.org "Topic and Service name mapping"): validation, expansion of
//! relative and private (`~`) names against the node, and remapping.
//!
//! Remap rules are matched on fully expanded names: `from` is expanded like a topic name of
//! the node, compared with the expanded topic, and on a match `to` is expanded and used. The
//! first matching rule wins (rcl order); node-targeted rules only apply to that node.

use crate::ros_args::Remap;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NameError {
    #[error("invalid name '{name}': {reason}")]
    Invalid { name: String, reason: &'static str },
}

fn invalid(name: &str, reason: &'static str) -> NameError {
    NameError::Invalid {
        name: name.to_string(),
        reason,
    }
}

/// Validate one token of a name (between slashes).
fn check_token(full: &str, token: &str) -> Result<(), NameError> {
    if token.is_empty() {
        return Err(invalid(
            full,
            "empty path element (repeated or trailing '/')",
        ));
    }
    if token.starts_with(|c: char| c.is_ascii_digit()) {
        return Err(invalid(full, "a path element must not start with a digit"));
    }
    if !token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(invalid(
            full,
            "only letters, digits, '_' and '/' are allowed",
        ));
    }
    if token.contains("__") {
        return Err(invalid(full, "repeated '_' is not allowed"));
    }
    Ok(())
}

/// Validate a node base name (`talker`).
pub fn validate_node_name(name: &str) -> Result<(), NameError> {
    if name.is_empty() {
        return Err(invalid(name, "node name is empty"));
    }
    if name.contains('/') {
        return Err(invalid(name, "node name must not contain '/'"));
    }
    check_token(name, name)
}

/// Normalise and validate a namespace: always absolute, no trailing slash except `/` itself.
pub fn normalize_namespace(ns: &str) -> Result<String, NameError> {
    let trimmed = ns.trim_end_matches('/');
    if trimmed.is_empty() {
        return Ok("/".to_string());
    }
    let abs = if trimmed.starts_with('/') {
        trimmed.to_string()
    } else {
        format!("/{trimmed}")
    };
    for t in abs[1..].split('/') {
        check_token(ns, t)?;
    }
    Ok(abs)
}

/// Fully qualified node name from a normalised namespace and base name.
pub fn fully_qualified_node_name(namespace: &str, node: &str) -> String {
    if namespace == "/" {
        format!("/{node}")
    } else {
        format!("{namespace}/{node}")
    }
}

/// Expand a topic name for a node: `/abs` stays, `rel` → `<ns>/rel`, `~` → `<ns>/<node>`,
/// `~/x` → `<ns>/<node>/x`, `{node}`/`{ns}`/`{namespace}` substitutions. The result is validated.
pub fn expand_topic_name(name: &str, namespace: &str, node: &str) -> Result<String, NameError> {
    if name.is_empty() {
        return Err(invalid(name, "topic name is empty"));
    }
    let fqn = fully_qualified_node_name(namespace, node);
    let ns_sub = if namespace == "/" { "" } else { namespace };
    let substituted = name
        .replace("{node}", node)
        .replace("{namespace}", ns_sub)
        .replace("{ns}", ns_sub);
    if substituted.contains(['{', '}']) {
        return Err(invalid(
            name,
            "unknown substitution (known: {node}, {ns}, {namespace})",
        ));
    }
    let expanded = if substituted == "~" {
        fqn
    } else if let Some(rest) = substituted.strip_prefix("~/") {
        format!("{fqn}/{rest}")
    } else if substituted.starts_with('~') {
        return Err(invalid(name, "'~' must be followed by '/'"));
    } else if substituted.starts_with('/') {
        substituted
    } else if namespace == "/" {
        format!("/{substituted}")
    } else {
        format!("{namespace}/{substituted}")
    };
    if expanded.ends_with('/') && expanded != "/" {
        return Err(invalid(name, "must not end with '/'"));
    }
    for t in expanded[1..].split('/') {
        check_token(name, t)?;
    }
    Ok(expanded)
}

/// Expand `name` and apply the first matching remap rule (names starting with `__` are not topic rules).
pub fn resolve_topic_name(
    name: &str,
    namespace: &str,
    node: &str,
    remaps: &[Remap],
) -> Result<String, NameError> {
    let expanded = expand_topic_name(name, namespace, node)?;
    for rule in remaps {
        if rule.from.starts_with("__") || rule.node.as_deref().is_some_and(|n| n != node) {
            continue;
        }
        let Ok(from) = expand_topic_name(&rule.from, namespace, node) else {
            continue;
        };
        if from == expanded {
            return expand_topic_name(&rule.to, namespace, node);
        }
    }
    Ok(expanded)
}

/// DDS topic name for a ROS topic (`/a/b` → `rt/a/b`).
pub fn dds_topic_name(ros_topic: &str) -> String {
    format!("rt{ros_topic}")
}

/// ROS topic for a DDS topic name, if it is a ROS topic (`rt/a/b` → `/a/b`).
pub fn ros_topic_from_dds(dds_topic: &str) -> Option<String> {
    dds_topic.strip_prefix("rt/").map(|rest| format!("/{rest}"))
}

/// ROS type name for a DDS type name (`pkg::msg::dds_::Type_` → `pkg/msg/Type`).
pub fn ros_type_from_dds(dds_type: &str) -> Option<String> {
    let parts: Vec<&str> = dds_type.split("::").collect();
    match parts.as_slice() {
        [pkg, kind, "dds_", ty] if ty.ends_with('_') => {
            Some(format!("{pkg}/{kind}/{}", &ty[..ty.len() - 1]))
        }
        _ => None,
    }
}

/// Split a ROS type name `pkg/msg/Type` (or `pkg/Type`) into package and type.
pub fn split_ros_type(ros_type: &str) -> Result<(String, String), NameError> {
    let parts: Vec<&str> = ros_type.split('/').collect();
    let (pkg, ty) = match parts.as_slice() {
        [pkg, "msg", ty] => (*pkg, *ty),
        [pkg, ty] => (*pkg, *ty),
        _ => return Err(invalid(ros_type, "a message type is written pkg/msg/Type")),
    };
    if pkg.is_empty() || ty.is_empty() || !ty.starts_with(|c: char| c.is_ascii_alphabetic()) {
        return Err(invalid(ros_type, "a message type is written pkg/msg/Type"));
    }
    Ok((pkg.to_string(), ty.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn remap(node: Option<&str>, from: &str, to: &str) -> Remap {
        Remap {
            node: node.map(str::to_string),
            from: from.into(),
            to: to.into(),
        }
    }

    #[test]
    fn expansion() {
        assert_eq!(
            expand_topic_name("chatter", "/", "talker").unwrap(),
            "/chatter"
        );
        assert_eq!(
            expand_topic_name("chatter", "/cell", "talker").unwrap(),
            "/cell/chatter"
        );
        assert_eq!(
            expand_topic_name("a/b", "/cell", "talker").unwrap(),
            "/cell/a/b"
        );
        assert_eq!(
            expand_topic_name("/abs", "/cell", "talker").unwrap(),
            "/abs"
        );
        assert_eq!(
            expand_topic_name("~", "/cell", "talker").unwrap(),
            "/cell/talker"
        );
        assert_eq!(
            expand_topic_name("~/status", "/cell", "talker").unwrap(),
            "/cell/talker/status"
        );
        assert_eq!(
            expand_topic_name("~/status", "/", "talker").unwrap(),
            "/talker/status"
        );
        assert_eq!(
            expand_topic_name("{node}/x", "/cell", "talker").unwrap(),
            "/cell/talker/x"
        );
        for bad in ["", "a//b", "a/", "1abc", "a-b", "~x", "a__b", "{foo}"] {
            assert!(
                expand_topic_name(bad, "/", "n").is_err(),
                "{bad:?} accepted"
            );
        }
    }

    #[test]
    fn remapping() {
        let rules = vec![
            remap(Some("other"), "chatter", "/wrong"),
            remap(None, "__node", "x"),
            remap(None, "chatter", "/talk"),
            remap(None, "/cell/image", "raw"),
            remap(None, "chatter", "/second"),
        ];
        assert_eq!(
            resolve_topic_name("chatter", "/", "talker", &rules).unwrap(),
            "/talk"
        );
        assert_eq!(
            resolve_topic_name("/chatter", "/", "talker", &rules).unwrap(),
            "/talk"
        );
        assert_eq!(
            resolve_topic_name("image", "/cell", "cam", &rules).unwrap(),
            "/cell/raw"
        );
        assert_eq!(
            resolve_topic_name("chatter", "/", "other", &rules).unwrap(),
            "/wrong"
        );
        assert_eq!(
            resolve_topic_name("unrelated", "/", "talker", &rules).unwrap(),
            "/unrelated"
        );
    }

    #[test]
    fn namespaces_and_dds_names() {
        assert_eq!(normalize_namespace("").unwrap(), "/");
        assert_eq!(normalize_namespace("cell/").unwrap(), "/cell");
        assert!(normalize_namespace("/a//b").is_err());
        assert_eq!(fully_qualified_node_name("/", "n"), "/n");
        assert_eq!(dds_topic_name("/a/b"), "rt/a/b");
        assert_eq!(ros_topic_from_dds("rt/a/b").as_deref(), Some("/a/b"));
        assert_eq!(ros_topic_from_dds("ros_discovery_info"), None);
        assert_eq!(
            ros_type_from_dds("std_msgs::msg::dds_::String_").as_deref(),
            Some("std_msgs/msg/String")
        );
        assert_eq!(ros_type_from_dds("DCPSParticipant"), None);
        assert_eq!(
            split_ros_type("pkg/msg/T").unwrap(),
            ("pkg".into(), "T".into())
        );
        assert_eq!(split_ros_type("pkg/T").unwrap(), ("pkg".into(), "T".into()));
        assert!(split_ros_type("T").is_err());
        assert!(validate_node_name("talker_1").is_ok());
        assert!(validate_node_name("1talker").is_err());
    }
}
