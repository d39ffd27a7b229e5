//! Building the DDS participant from the ROS 2 environment.
//!
//! LOCALHOST restricts RustDDS to 127.0.0.1 with `with_only_networks`: multicast discovery then
//! runs only on `lo` (when `lo` has the MULTICAST flag, as inside `tools/isolated`), unicast
//! locators advertise 127.0.0.1, and RustDDS's same-host loopback (on by default) also sends SPDP
//! to the well-known localhost unicast ports, so discovery works even without multicast on `lo`.
//!
//! Security (DDS-Security through RustDDS's builtin plugins) is added when the ROS 2 security
//! environment asks for it (`metrocell_security::environment` states rcl's rules).

use std::net::{IpAddr, Ipv4Addr};

use std::path::Path;

use rustdds::{DomainParticipant, DomainParticipantBuilder, DomainParticipantSecurityConfigFiles};

use crate::environment::{DdsEnvironment, DiscoveryRange};
use crate::error::{create_error, NodeError};

/// The participant builder for an environment (exposed so tools can add settings).
pub fn participant_builder(env: &DdsEnvironment) -> DomainParticipantBuilder {
    let builder = DomainParticipantBuilder::new(env.domain_id);
    match env.discovery_range {
        DiscoveryRange::Localhost => builder
            .with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)])
            .same_host_loopback(true),
        // No interface at all: nothing is announced and no localhost peers are contacted.
        DiscoveryRange::Off => builder
            .with_only_networks(Vec::<IpAddr>::new())
            .same_host_loopback(false),
        DiscoveryRange::Subnet | DiscoveryRange::SystemDefault => builder,
    }
}

/// Create the participant (secured with the enclave's files when `enclave_dir` is given) and wrap
/// it in a ros2-client context.
pub fn create_context(
    env: &DdsEnvironment,
    enclave_dir: Option<&Path>,
) -> Result<ros2_client::Context, NodeError> {
    let mut builder = participant_builder(env);
    if let Some(dir) = enclave_dir {
        // sros2 writes identity keys unencrypted: no password.
        builder = builder.builtin_security(
            DomainParticipantSecurityConfigFiles::with_ros_default_names(dir, String::new()),
        );
    }
    let participant: DomainParticipant = builder.build().map_err(|e| {
        let secured = match enclave_dir {
            Some(d) => format!(" secured with the enclave in {}", d.display()),
            None => String::new(),
        };
        create_error(
            format!("DDS participant in domain {}{secured}", env.domain_id),
            e,
        )
    })?;
    ros2_client::Context::from_domain_participant(participant)
        .map_err(|e| create_error("ROS 2 context", e))
}
