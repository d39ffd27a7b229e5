//! Guard for tests that open DDS participants: they must run in a private network namespace
//! so that no discovery traffic leaves the machine.

/// Network interfaces of this process's network namespace (`/proc/self/net/dev`).
fn interfaces() -> std::io::Result<Vec<String>> {
    let text = std::fs::read_to_string("/proc/self/net/dev")?;
    Ok(text
        .lines()
        .skip(2)
        .filter_map(|l| l.split(':').next())
        .map(|n| n.trim().to_string())
        .collect())
}

/// Panics unless this process's network namespace has no interface but the loopback, as in
/// `tests/isolated` and `tests/run`. The namespace itself is checked, not an environment
/// variable, so a test cannot be talked into opening DDS on the host network.
pub fn require_isolated_network() {
    let found = interfaces().unwrap_or_else(|e| panic!("cannot list network interfaces (/proc/self/net/dev: {e}); DDS tests need a private network namespace"));
    let others: Vec<&String> = found.iter().filter(|n| *n != "lo").collect();
    if !others.is_empty() {
        panic!(
            "DDS tests must run in a private network namespace, but this one has {others:?}: use tests/run or tests/isolated \
             (e.g. `tests/isolated cargo test -p metrocell-node`)"
        );
    }
}

/// A child process (a node under test) killed and reaped when the guard drops, so a failing
/// test leaves no node running in the namespace.
pub struct KillOnDrop(pub std::process::Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A client of one node's `rcl_interfaces/srv/SetParameters` service (as `ros2 param set` uses),
/// kept for several requests: a ROS 2 service answers on a topic of its own, and an answer written
/// before the server has discovered the client's reader of it is lost. The first answer proves
/// both directions matched; a new client per request would race discovery again each time (seen
/// under load: the second of two requests from fresh clients unanswered for 20 s).
pub struct RemoteParameterClient {
    target: String,
    client: ros2_client::Client<
        ros2_client::rcl_interfaces::SetParametersRequest,
        ros2_client::rcl_interfaces::SetParametersResponse,
    >,
}

impl RemoteParameterClient {
    /// A client, on `client_node` (another participant), of the node `target` (fully qualified,
    /// e.g. `/tracker`).
    pub fn new(client_node: &mut crate::MetrocellNode, target: &str) -> Result<Self, String> {
        use ros2_client::rcl_interfaces::{SetParametersRequest, SetParametersResponse};
        let service = ros2_client::Name::new(target, "set_parameters")
            .map_err(|e| format!("service name {target}/set_parameters: {e:?}"))?;
        let qos = crate::qos::reliable();
        let client = client_node
            .ros_node()
            .create_client::<SetParametersRequest, SetParametersResponse>(
                ros2_client::ServiceMapping::Enhanced,
                &service,
                &ros2_client::ServiceTypeName::new("rcl_interfaces", "SetParameters"),
                qos.clone(),
                qos,
            )
            .map_err(|e| format!("client of {target}/set_parameters: {e:?}"))?;
        Ok(Self {
            target: target.to_string(),
            client,
        })
    }

    /// Set parameter `name` to `value`. `Err`: the node refused (its reason) or did not answer
    /// within `timeout`.
    pub fn set(
        &mut self,
        client_node: &mut crate::MetrocellNode,
        name: &str,
        value: crate::ParamValue,
        timeout: std::time::Duration,
    ) -> Result<(), String> {
        use ros2_client::parameters::raw;
        use ros2_client::rcl_interfaces::SetParametersRequest;
        let target = &self.target;
        let request = SetParametersRequest {
            parameter: vec![raw::Parameter {
                name: name.to_string(),
                value: raw::ParameterValue::from(value.to_ros()),
            }],
        };
        let deadline = std::time::Instant::now() + timeout;
        // The request is sent once, when the service is matched (reliable from then on). Resending
        // on a slow answer would set the parameter twice, and a node that acts on each set (then
        // resets it, like the tracker's `reregister`) would act twice.
        if block_on_within(
            self.client.wait_for_service(client_node.ros_node()),
            timeout,
        )
        .is_none()
        {
            return Err(format!(
                "no {target}/set_parameters service matched within {timeout:?}"
            ));
        }
        let id = self
            .client
            .send_request(request)
            .map_err(|e| format!("request to {target}/set_parameters: {e:?}"))?;
        while std::time::Instant::now() < deadline {
            match self.client.receive_response() {
                Ok(Some((rid, response))) if rid == id => {
                    let r = response
                        .results
                        .first()
                        .ok_or("an empty SetParameters response")?;
                    return if r.successful {
                        Ok(())
                    } else {
                        Err(r.reason.clone())
                    };
                }
                Ok(_) => std::thread::sleep(std::time::Duration::from_millis(10)),
                Err(e) => return Err(format!("response from {target}/set_parameters: {e:?}")),
            }
        }
        Err(format!(
            "no answer from {target}/set_parameters within {timeout:?}"
        ))
    }
}

/// Set parameter `name` of the node `target` once, through a [`RemoteParameterClient`] made for
/// it (several requests: keep one client). `Err`: the node refused (its reason) or did not answer.
pub fn set_remote_parameter(
    client_node: &mut crate::MetrocellNode,
    target: &str,
    name: &str,
    value: crate::ParamValue,
    timeout: std::time::Duration,
) -> Result<(), String> {
    RemoteParameterClient::new(client_node, target)?.set(client_node, name, value, timeout)
}

use crate::blocking::block_on_within;

#[cfg(test)]
mod tests {
    #[test]
    fn the_loopback_is_always_listed() {
        assert!(super::interfaces().unwrap().iter().any(|n| n == "lo"));
    }
}
