//! The ROS 2 environment variables that decide which DDS network a node joins:
//! `ROS_DOMAIN_ID` (default 0, valid 0..=232), `ROS_AUTOMATIC_DISCOVERY_RANGE`
//! (`LOCALHOST`, `SUBNET`, `OFF`, `SYSTEM_DEFAULT`; unset or empty = `SUBNET`) and the legacy
//! `ROS_LOCALHOST_ONLY=1`, which forces `LOCALHOST` (the stricter setting wins when both are set).

/// Which peers automatic discovery may reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiscoveryRange {
    /// No discovery at all (the participant announces no locators).
    Off,
    /// Only this host: multicast and locators restricted to 127.0.0.1.
    Localhost,
    /// Every multicast-capable interface (the DDS default).
    Subnet,
    /// Whatever the DDS implementation does by default (same as `Subnet` for RustDDS).
    SystemDefault,
}

/// The DDS-related environment of a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DdsEnvironment {
    pub domain_id: u16,
    pub discovery_range: DiscoveryRange,
}

/// Largest domain id ROS 2 accepts (port arithmetic of the RTPS mapping).
pub const MAX_DOMAIN_ID: u16 = 232;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum EnvError {
    #[error("ROS_DOMAIN_ID='{value}' is not a valid domain id: expected an integer in 0..={MAX_DOMAIN_ID}")]
    DomainId { value: String },
    #[error("ROS_AUTOMATIC_DISCOVERY_RANGE='{value}' is not valid: expected LOCALHOST, SUBNET, OFF or SYSTEM_DEFAULT")]
    DiscoveryRange { value: String },
    #[error("ROS_LOCALHOST_ONLY='{value}' is not valid: expected 0 or 1")]
    LocalhostOnly { value: String },
}

impl DdsEnvironment {
    /// Read from the process environment.
    pub fn from_env() -> Result<DdsEnvironment, EnvError> {
        DdsEnvironment::from_lookup(|k| std::env::var(k).ok())
    }

    /// Read through a lookup function (pure; for tests and launchers).
    pub fn from_lookup(get: impl Fn(&str) -> Option<String>) -> Result<DdsEnvironment, EnvError> {
        let domain_id = match get("ROS_DOMAIN_ID")
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
        {
            None => 0,
            Some(v) => match v.parse::<u16>() {
                Ok(d) if d <= MAX_DOMAIN_ID => d,
                _ => return Err(EnvError::DomainId { value: v }),
            },
        };
        let mut discovery_range = match get("ROS_AUTOMATIC_DISCOVERY_RANGE")
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
        {
            None => DiscoveryRange::Subnet,
            Some(v) => match v.to_ascii_uppercase().as_str() {
                "LOCALHOST" => DiscoveryRange::Localhost,
                "SUBNET" => DiscoveryRange::Subnet,
                "OFF" => DiscoveryRange::Off,
                "SYSTEM_DEFAULT" => DiscoveryRange::SystemDefault,
                _ => return Err(EnvError::DiscoveryRange { value: v }),
            },
        };
        match get("ROS_LOCALHOST_ONLY")
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .as_deref()
        {
            None | Some("0") => {}
            Some("1") => {
                if discovery_range != DiscoveryRange::Off {
                    discovery_range = DiscoveryRange::Localhost;
                }
            }
            Some(v) => {
                return Err(EnvError::LocalhostOnly {
                    value: v.to_string(),
                })
            }
        }
        Ok(DdsEnvironment {
            domain_id,
            discovery_range,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(pairs: &[(&str, &str)]) -> Result<DdsEnvironment, EnvError> {
        let pairs: Vec<(String, String)> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        DdsEnvironment::from_lookup(|k| {
            pairs.iter().find(|(kk, _)| kk == k).map(|(_, v)| v.clone())
        })
    }

    #[test]
    fn defaults() {
        assert_eq!(
            env(&[]).unwrap(),
            DdsEnvironment {
                domain_id: 0,
                discovery_range: DiscoveryRange::Subnet
            }
        );
        assert_eq!(env(&[("ROS_DOMAIN_ID", "")]).unwrap().domain_id, 0);
    }

    #[test]
    fn domain_id_is_validated() {
        assert_eq!(env(&[("ROS_DOMAIN_ID", "42")]).unwrap().domain_id, 42);
        assert_eq!(env(&[("ROS_DOMAIN_ID", "232")]).unwrap().domain_id, 232);
        for bad in ["233", "-1", "x", "1.5"] {
            let e = env(&[("ROS_DOMAIN_ID", bad)]).unwrap_err();
            assert!(
                e.to_string().contains(bad) && e.to_string().contains("0..=232"),
                "{e}"
            );
        }
    }

    #[test]
    fn discovery_range() {
        assert_eq!(
            env(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")])
                .unwrap()
                .discovery_range,
            DiscoveryRange::Localhost
        );
        assert_eq!(
            env(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "off")])
                .unwrap()
                .discovery_range,
            DiscoveryRange::Off
        );
        assert_eq!(
            env(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "SYSTEM_DEFAULT")])
                .unwrap()
                .discovery_range,
            DiscoveryRange::SystemDefault
        );
        assert_eq!(
            env(&[("ROS_LOCALHOST_ONLY", "1")]).unwrap().discovery_range,
            DiscoveryRange::Localhost
        );
        assert_eq!(
            env(&[
                ("ROS_LOCALHOST_ONLY", "1"),
                ("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET")
            ])
            .unwrap()
            .discovery_range,
            DiscoveryRange::Localhost
        );
        assert_eq!(
            env(&[("ROS_LOCALHOST_ONLY", "0")]).unwrap().discovery_range,
            DiscoveryRange::Subnet
        );
        assert!(env(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "LAN")])
            .unwrap_err()
            .to_string()
            .contains("LAN"));
        assert!(env(&[("ROS_LOCALHOST_ONLY", "yes")]).is_err());
    }
}
