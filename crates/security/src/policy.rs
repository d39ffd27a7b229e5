//! SROS2 access-control policies (`<policy>` files, the format `ros2 security create_permission`
//! reads) and the DDS-Security permissions documents they become.
//!
//! A policy names enclaves; each enclave has profiles (a node in a namespace), each profile grants
//! or denies `topics` (`publish`, `subscribe`), `services` (`request`, `reply`) and `actions`
//! (`call`, `execute`) with the values `ALLOW` or `DENY`. A name is absolute (`/x`), private
//! (`~/x`, under the profile's node: `~` is replaced by the node's name, as sros2 does) or relative (under the profile's namespace); `*` is a wildcard
//! as DDS-Security reads it (fnmatch). ROS 2 names become DDS topic names by the ROS 2 mangling:
//! topics `rt/<name>`, service requests `rq/<name>Request`, replies `rr/<name>Reply`, an action's
//! three services under `<name>/_action/` and its `feedback` and `status` topics.
//!
//! The translation follows `sros2`'s `permissions.xsl` rule for rule: one grant per enclave with
//! subject `CN=<enclave>`, its denials (a `deny_rule`) before its allowances (an `allow_rule`),
//! and `DENY` by default, so that what the policy does not name is refused.

use crate::error::SecurityError;
use std::path::Path;

/// What a rule says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Allow,
    Deny,
}

/// A DDS-level permission: `publish` (write) or `subscribe` (read) on DDS topic names.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DdsTopics {
    pub publish: Vec<String>,
    pub subscribe: Vec<String>,
}

/// One enclave's grant, in DDS terms.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EnclaveGrant {
    /// The enclave's path, e.g. `/cell/twin` (the certificate's common name).
    pub enclave: String,
    pub deny: DdsTopics,
    pub allow: DdsTopics,
}

/// The policy every `create-enclave` starts from: everything allowed (sros2's default policy).
pub const DEFAULT_POLICY: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<policy version="0.2.0">
  <enclaves>
    <enclave path="/">
      <profiles>
        <profile ns="/" node="default">
          <topics publish="ALLOW" subscribe="ALLOW"><topic>/*</topic></topics>
          <services reply="ALLOW" request="ALLOW"><service>/*</service></services>
          <actions call="ALLOW" execute="ALLOW"><action>/*</action></actions>
        </profile>
      </profiles>
    </enclave>
  </enclaves>
</policy>
"#;

/// Read a policy file and return the grants of its enclaves.
pub fn read_policy(path: &Path) -> Result<Vec<EnclaveGrant>, SecurityError> {
    let text = std::fs::read_to_string(path).map_err(crate::error::io_error(path))?;
    parse_policy(&text).map_err(|why| SecurityError::Invalid {
        path: path.to_path_buf(),
        why,
    })
}

/// Parse a policy's text (`<policy><enclaves><enclave path=…>`, or the older
/// `<contexts><context path=…>` spelling).
pub fn parse_policy(text: &str) -> Result<Vec<EnclaveGrant>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("not XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "policy" {
        return Err(format!(
            "the root element is <{}>, expected <policy> (an sros2 policy file)",
            root.tag_name().name()
        ));
    }
    let mut grants = Vec::new();
    for group in root.children().filter(|n| n.is_element()) {
        let member = match group.tag_name().name() {
            "enclaves" => "enclave",
            "contexts" => "context",
            other => {
                return Err(format!(
                    "unexpected <{other}> in <policy>: expected <enclaves>"
                ))
            }
        };
        for enclave in group.children().filter(|n| n.has_tag_name(member)) {
            let path = enclave.attribute("path").ok_or_else(|| {
                format!("<{member}> at byte {} has no path=", enclave.range().start)
            })?;
            validate_enclave_name(path)?;
            let mut grant = EnclaveGrant {
                enclave: path.to_string(),
                deny: DdsTopics::default(),
                allow: DdsTopics::default(),
            };
            for profiles in enclave.children().filter(|n| n.has_tag_name("profiles")) {
                for profile in profiles.children().filter(|n| n.has_tag_name("profile")) {
                    add_profile(&mut grant, profile)?;
                }
            }
            dedup(&mut grant.allow);
            dedup(&mut grant.deny);
            grants.push(grant);
        }
    }
    if grants.is_empty() {
        return Err("the policy names no enclave (<enclaves><enclave path=\"/…\">)".into());
    }
    Ok(grants)
}

fn dedup(t: &mut DdsTopics) {
    for v in [&mut t.publish, &mut t.subscribe] {
        v.sort();
        v.dedup();
    }
}

fn add_profile(grant: &mut EnclaveGrant, profile: roxmltree::Node) -> Result<(), String> {
    let ns = profile.attribute("ns").unwrap_or("/");
    let node = profile.attribute("node").unwrap_or("");
    for rule in profile.children().filter(|n| n.is_element()) {
        let (item, verbs): (&str, &[&str]) = match rule.tag_name().name() {
            "topics" => ("topic", &["publish", "subscribe"]),
            "services" => ("service", &["request", "reply"]),
            "actions" => ("action", &["call", "execute"]),
            other => {
                return Err(format!(
                    "unexpected <{other}> in profile '{node}': expected <topics>, <services> or <actions>"
                ))
            }
        };
        let names: Vec<String> = rule
            .children()
            .filter(|n| n.has_tag_name(item))
            .map(|n| fully_qualified(n.text().unwrap_or("").trim(), ns, node))
            .collect::<Result<_, _>>()?;
        for attr in rule.attributes() {
            if !verbs.contains(&attr.name()) {
                return Err(format!(
                    "<{}> in profile '{node}' has {}=: expected one of {verbs:?}",
                    rule.tag_name().name(),
                    attr.name()
                ));
            }
            let verdict = match attr.value() {
                "ALLOW" => Verdict::Allow,
                "DENY" => Verdict::Deny,
                v => {
                    return Err(format!(
                        "{}=\"{v}\" in profile '{node}': expected ALLOW or DENY",
                        attr.name()
                    ))
                }
            };
            let target = match verdict {
                Verdict::Allow => &mut grant.allow,
                Verdict::Deny => &mut grant.deny,
            };
            for name in &names {
                dds_topics(attr.name(), name, target);
            }
        }
    }
    Ok(())
}

/// The ROS 2 name a policy entry stands for (sros2's rule: `/x` as is, `~x` under the node,
/// otherwise under the namespace).
fn fully_qualified(name: &str, ns: &str, node: &str) -> Result<String, String> {
    if name.is_empty() {
        return Err(format!("an empty name in profile '{node}'"));
    }
    let ns = if ns.ends_with('/') {
        ns.to_string()
    } else {
        format!("{ns}/")
    };
    Ok(if name.starts_with('/') {
        name.to_string()
    } else if let Some(rest) = name.strip_prefix('~') {
        format!("{ns}{node}{rest}")
    } else {
        format!("{ns}{name}")
    })
}

/// The DDS topics one verb on one ROS 2 name covers (the ROS 2 topic-name mangling).
fn dds_topics(verb: &str, name: &str, out: &mut DdsTopics) {
    let action = |svc: &str, suffix: &str| format!("{svc}{name}/_action/{suffix}");
    let action_requests = || {
        ["cancel_goal", "get_result", "send_goal"]
            .map(|s| action("rq", &format!("{s}Request")))
            .to_vec()
    };
    let action_replies = || {
        let mut v: Vec<String> = ["cancel_goal", "get_result", "send_goal"]
            .map(|s| action("rr", &format!("{s}Reply")))
            .to_vec();
        v.push(action("rt", "feedback"));
        v.push(action("rt", "status"));
        v
    };
    match verb {
        "publish" => out.publish.push(format!("rt{name}")),
        "subscribe" => out.subscribe.push(format!("rt{name}")),
        "request" => {
            out.publish.push(format!("rq{name}Request"));
            out.subscribe.push(format!("rr{name}Reply"));
        }
        "reply" => {
            out.publish.push(format!("rr{name}Reply"));
            out.subscribe.push(format!("rq{name}Request"));
        }
        "call" => {
            out.publish.extend(action_requests());
            out.subscribe.extend(action_replies());
        }
        "execute" => {
            out.publish.extend(action_replies());
            out.subscribe.extend(action_requests());
        }
        _ => unreachable!("verbs are checked by add_profile"),
    }
}

/// An enclave name is an absolute ROS 2 namespace: `/`, or `/` followed by `/`-separated tokens of
/// letters, digits and `_`, none starting with a digit, no `//`, no trailing `/`.
pub fn validate_enclave_name(name: &str) -> Result<(), String> {
    let bad = |why: &str| Err(format!("enclave name '{name}' {why}"));
    if name == "/" {
        return Ok(());
    }
    let Some(rest) = name.strip_prefix('/') else {
        return bad("must start with '/' (an absolute name such as /cell/twin)");
    };
    for token in rest.split('/') {
        if token.is_empty() {
            return bad("has an empty part ('//' or a trailing '/')");
        }
        if !token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return bad("may hold only letters, digits, '_' and '/'");
        }
        if token.starts_with(|c: char| c.is_ascii_digit()) {
            return bad("has a part starting with a digit");
        }
    }
    Ok(())
}

/// The ROS 2 graph's own DDS topic (rmw_dds_common's, no `rt/` prefix): every node publishes and
/// reads its node and endpoint names there, so every grant allows it (sros2's
/// `allow_ros_discovery_topic`). It carries names, not data.
pub const ROS_DISCOVERY_TOPIC: &str = "ros_discovery_info";

/// The DDS-Security permissions document (`permissions.xml`) of a grant in a domain, valid from
/// `not_before` to `not_after` (UTC, `YYYY-MM-DDThh:mm:ss`).
pub fn permissions_document(
    grant: &EnclaveGrant,
    domain_id: u16,
    not_before: &str,
    not_after: &str,
) -> String {
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    x.push_str("<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd\">\n");
    x.push_str("  <permissions>\n");
    x.push_str(&format!(
        "    <grant name=\"{}\">\n",
        escape(&grant.enclave)
    ));
    x.push_str(&format!(
        "      <subject_name>CN={}</subject_name>\n",
        escape(&grant.enclave)
    ));
    x.push_str(&format!(
        "      <validity>\n        <not_before>{not_before}</not_before>\n        <not_after>{not_after}</not_after>\n      </validity>\n"
    ));
    let mut allow = grant.allow.clone();
    allow.publish.push(ROS_DISCOVERY_TOPIC.into());
    allow.subscribe.push(ROS_DISCOVERY_TOPIC.into());
    for (tag, topics) in [("deny_rule", &grant.deny), ("allow_rule", &allow)] {
        if topics.publish.is_empty() && topics.subscribe.is_empty() {
            continue;
        }
        x.push_str(&format!("      <{tag}>\n        <domains>\n          <id>{domain_id}</id>\n        </domains>\n"));
        for (verb, list) in [
            ("publish", &topics.publish),
            ("subscribe", &topics.subscribe),
        ] {
            if list.is_empty() {
                continue;
            }
            x.push_str(&format!("        <{verb}>\n          <topics>\n"));
            for t in list {
                x.push_str(&format!("            <topic>{}</topic>\n", escape(t)));
            }
            x.push_str(&format!("          </topics>\n        </{verb}>\n"));
        }
        x.push_str(&format!("      </{tag}>\n"));
    }
    x.push_str("      <default>DENY</default>\n    </grant>\n  </permissions>\n</dds>\n");
    x
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_mangled_as_ros2_does() {
        let p = r#"<policy version="0.2.0"><enclaves><enclave path="/cell/tracker"><profiles>
            <profile ns="/cell" node="tracker">
              <topics subscribe="ALLOW"><topic>tracker/measurements</topic><topic>/clock</topic></topics>
              <topics publish="ALLOW"><topic>~/status</topic></topics>
              <topics publish="DENY"><topic>/joint_states</topic></topics>
              <services reply="ALLOW"><service>~/get_parameters</service></services>
              <actions call="ALLOW"><action>/move</action></actions>
            </profile></profiles></enclave></enclaves></policy>"#;
        let g = &parse_policy(p).unwrap()[0];
        assert_eq!(g.enclave, "/cell/tracker");
        assert!(g
            .allow
            .subscribe
            .contains(&"rt/cell/tracker/measurements".to_string()));
        assert!(g.allow.subscribe.contains(&"rt/clock".to_string()));
        assert!(g
            .allow
            .publish
            .contains(&"rt/cell/tracker/status".to_string()));
        assert!(g
            .allow
            .publish
            .contains(&"rr/cell/tracker/get_parametersReply".to_string()));
        assert!(g
            .allow
            .subscribe
            .contains(&"rq/cell/tracker/get_parametersRequest".to_string()));
        assert!(g
            .allow
            .subscribe
            .contains(&"rr/move/_action/send_goalReply".to_string()));
        assert!(g
            .allow
            .subscribe
            .contains(&"rt/move/_action/feedback".to_string()));
        assert!(g
            .allow
            .publish
            .contains(&"rq/move/_action/cancel_goalRequest".to_string()));
        assert_eq!(g.deny.publish, vec!["rt/joint_states".to_string()]);
    }

    #[test]
    fn the_permissions_document_denies_first_and_by_default() {
        let g = &parse_policy(DEFAULT_POLICY).unwrap()[0];
        let mut g = g.clone();
        g.deny.publish.push("rt/secret".into());
        let x = permissions_document(&g, 7, "2026-01-01T00:00:00", "2036-01-01T00:00:00");
        let deny = x.find("<deny_rule>").unwrap();
        let allow = x.find("<allow_rule>").unwrap();
        assert!(deny < allow);
        assert!(x.contains("<subject_name>CN=/</subject_name>"));
        assert!(x.contains("<id>7</id>"));
        assert!(x.contains("<topic>rt/*</topic>"));
        assert!(x.contains("<topic>rq/*Request</topic>"));
        let allow_rule = &x[allow..];
        assert_eq!(
            allow_rule
                .matches("<topic>ros_discovery_info</topic>")
                .count(),
            2
        );
        assert!(x.trim_end().ends_with(
            "<default>DENY</default>\n    </grant>\n  </permissions>\n</dds>".trim_end()
        ));
        roxmltree::Document::parse(&x).expect("well-formed XML");
    }

    #[test]
    fn bad_policies_are_refused_with_the_reason() {
        for (p, why) in [
            ("<nope/>", "expected <policy>"),
            ("<policy><enclaves/></policy>", "names no enclave"),
            (
                r#"<policy><enclaves><enclave path="cell"/></enclaves></policy>"#,
                "must start with '/'",
            ),
            (
                r#"<policy><enclaves><enclave path="/a"><profiles><profile ns="/" node="n"><topics publish="MAYBE"><topic>x</topic></topics></profile></profiles></enclave></enclaves></policy>"#,
                "expected ALLOW or DENY",
            ),
            (
                r#"<policy><enclaves><enclave path="/a"><profiles><profile ns="/" node="n"><topics write="ALLOW"><topic>x</topic></topics></profile></profiles></enclave></enclaves></policy>"#,
                "has write=",
            ),
        ] {
            let e = parse_policy(p).unwrap_err();
            assert!(e.contains(why), "{p}: {e}");
        }
        for ok in ["/", "/a", "/cell_1/twin"] {
            validate_enclave_name(ok).unwrap();
        }
        for bad in ["", "a", "/a/", "//a", "/1a", "/a-b"] {
            assert!(validate_enclave_name(bad).is_err(), "{bad}");
        }
    }
}
