//! Topics seen through DDS discovery, in ROS terms (for `metrocell topic list`).

/// A discovered ROS topic and its message type.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct TopicInfo {
    /// ROS topic name, e.g. `/diagnostics`.
    pub name: String,
    /// ROS type name, e.g. `diagnostic_msgs/msg/DiagnosticArray`.
    pub type_name: String,
}

/// Convert DDS (topic, type) pairs into ROS topics: keeps only `rt/` topics with ROS-shaped
/// type names, sorted and without duplicates.
pub fn ros_topics_from_dds<'a>(
    dds: impl IntoIterator<Item = (&'a str, &'a str)>,
) -> Vec<TopicInfo> {
    let mut out: Vec<TopicInfo> = dds
        .into_iter()
        .filter_map(|(topic, ty)| {
            Some(TopicInfo {
                name: crate::names::ros_topic_from_dds(topic)?,
                type_name: crate::names::ros_type_from_dds(ty)?,
            })
        })
        .collect();
    out.sort();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_ros_topics_remain() {
        let t = ros_topics_from_dds([
            ("rt/rosout", "rcl_interfaces::msg::dds_::Log_"),
            (
                "ros_discovery_info",
                "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_",
            ),
            ("rt/a/b", "pkg::msg::dds_::T_"),
            (
                "rq/x/get_parametersRequest",
                "rcl_interfaces::srv::dds_::GetParameters_Request_",
            ),
            ("rt/a/b", "pkg::msg::dds_::T_"),
        ]);
        assert_eq!(
            t,
            vec![
                TopicInfo {
                    name: "/a/b".into(),
                    type_name: "pkg/msg/T".into()
                },
                TopicInfo {
                    name: "/rosout".into(),
                    type_name: "rcl_interfaces/msg/Log".into()
                },
            ]
        );
    }
}
