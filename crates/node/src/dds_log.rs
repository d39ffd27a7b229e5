//! What the DDS stack itself says, on stderr when asked: RustDDS reports through the `log`
//! facade (lost participants, rediscovery, socket errors), which no node listened to, so a
//! network fault left no trace of what DDS did about it. `METROCELL_DDS_LOG=LEVEL` (error, warn,
//! info, debug, trace; unset = nothing) prints each record at or above LEVEL as
//! `[DDS LEVEL] [seconds.nanos] [target]: message`.
//!
//! A secured node (DDS Security on) without `METROCELL_DDS_LOG` still says why DDS refused a
//! participant: RustDDS's security events (a failed authentication handshake, an access-control
//! check that did not pass, data from a participant that is not authenticated) are printed as the
//! node's WARN lines, `[WARN] [seconds.nanos] [<node>.dds_security]: …`, each distinct text at
//! most once per [`SECURITY_EVENT_REPEAT_S`] (a refused peer retries its handshake every second).

use crate::logging::system_time_ns;

struct StderrLog;

impl log::Log for StderrLog {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::max_level()
    }

    fn log(&self, record: &log::Record) {
        if self.enabled(record.metadata()) {
            let ns = system_time_ns();
            eprintln!(
                "[DDS {}] [{}.{:09}] [{}]: {}",
                record.level(),
                ns.div_euclid(1_000_000_000),
                ns.rem_euclid(1_000_000_000),
                record.target(),
                record.args()
            );
        }
    }

    fn flush(&self) {}
}

/// Seconds before the same security event is printed again.
pub const SECURITY_EVENT_REPEAT_S: u64 = 30;

/// Whether a RustDDS record is a security event worth a secured node's log: what its
/// authentication, access-control and secure-discovery code reports at WARN or above, the refusals
/// it reports at INFO, and the unprotected messages its receiver drops. (Its crypto plugin's
/// "Could not find a remote EndpointCryptoHandle", logged while keys are still being exchanged
/// with a peer that is being admitted, is not one.)
pub fn is_security_event(target: &str, level: log::Level, message: &str) -> bool {
    if target.starts_with("rustdds::rtps::message_receiver") {
        return message.contains("unprotected message");
    }
    // Keys still being exchanged with a peer being admitted: retried by RustDDS, not a refusal.
    if [
        "EndpointCryptoHandle",
        "trying again later",
        "not related to the message",
    ]
    .iter()
    .any(|w| message.contains(w))
    {
        return false;
    }
    let security = [
        "rustdds::discovery::secure_discovery",
        "rustdds::security::authentication",
        "rustdds::security::access_control",
    ]
    .iter()
    .any(|t| target.starts_with(t));
    security
        && (level <= log::Level::Warn
            || [
                "did not pass",
                "ot allowed",
                "failed",
                "denied",
                "non-authenticated",
                "not matching",
                "does not verify",
            ]
            .iter()
            .any(|w| message.contains(w)))
}

/// What [`is_security_event`] can accept, judged without formatting the message.
fn may_be_security_event(metadata: &log::Metadata) -> bool {
    let target = metadata.target();
    if target.starts_with("rustdds::rtps::message_receiver") {
        return metadata.level() <= log::Level::Warn;
    }
    [
        "rustdds::discovery::secure_discovery",
        "rustdds::security::authentication",
        "rustdds::security::access_control",
    ]
    .iter()
    .any(|t| target.starts_with(t))
}

struct SecurityEventLog {
    node: String,
    last_printed: std::sync::Mutex<std::collections::HashMap<String, std::time::Instant>>,
}

impl log::Log for SecurityEventLog {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::Level::Info
            && (metadata
                .target()
                .starts_with("rustdds::discovery::secure_discovery")
                || metadata.target().starts_with("rustdds::security"))
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) || !may_be_security_event(record.metadata()) {
            return;
        }
        // Formatted only now: RustDDS logs at INFO on its data path too.
        let message = record.args().to_string();
        if !is_security_event(record.target(), record.level(), &message) {
            return;
        }
        let now = std::time::Instant::now();
        {
            let Ok(mut last) = self.last_printed.lock() else {
                return;
            };
            if last.get(&message).is_some_and(|t| {
                now.duration_since(*t) < std::time::Duration::from_secs(SECURITY_EVENT_REPEAT_S)
            }) {
                return;
            }
            if last.len() > 1000 {
                last.clear();
            }
            last.insert(message.clone(), now);
        }
        let ns = system_time_ns();
        eprintln!(
            "[WARN] [{}.{:09}] [{}.dds_security]: {message}",
            ns.div_euclid(1_000_000_000),
            ns.rem_euclid(1_000_000_000),
            self.node
        );
    }

    fn flush(&self) {}
}

/// For a secured node: print DDS security events unless `METROCELL_DDS_LOG` installed the full
/// bridge already (then they are among its lines).
pub fn install_security_events(node: &str) {
    let logger = Box::new(SecurityEventLog {
        node: node.to_string(),
        last_printed: Default::default(),
    });
    if log::set_boxed_logger(logger).is_ok() {
        log::set_max_level(log::LevelFilter::Info);
    }
}

/// The level `METROCELL_DDS_LOG` asks for, or why it is not one.
pub fn dds_log_level(value: Option<&str>) -> Result<Option<log::LevelFilter>, String> {
    match value.map(str::trim) {
        None | Some("") => Ok(None),
        Some(v) => v.parse::<log::LevelFilter>().map(Some).map_err(|_| {
            format!("METROCELL_DDS_LOG='{v}' is not a level: use error, warn, info, debug or trace")
        }),
    }
}

/// Installs the stderr bridge when `METROCELL_DDS_LOG` asks for it (once per process; a second
/// call, or another logger already installed, leaves things as they are). Returns a warning for a
/// value that is not a level.
pub fn install_from_env() -> Option<String> {
    match dds_log_level(std::env::var("METROCELL_DDS_LOG").ok().as_deref()) {
        Ok(Some(level)) => {
            if log::set_logger(&StderrLog).is_ok() {
                log::set_max_level(level);
            }
            None
        }
        Ok(None) => None,
        Err(e) => Some(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn security_events_are_refusals_from_the_security_code_only() {
        let auth = "rustdds::discovery::secure_discovery";
        assert!(is_security_event(
            auth,
            log::Level::Error,
            "Replying to a handshake request failed: Certificate signature verification failure"
        ));
        assert!(is_security_event(
            auth,
            log::Level::Info,
            "Access control check did not pass for participant X to read topic rt/secret."
        ));
        assert!(!is_security_event(
            auth,
            log::Level::Info,
            "Access control check passed for participant X to read topic rt/secret."
        ));
        assert!(is_security_event(
            "rustdds::rtps::message_receiver",
            log::Level::Error,
            "Received an unprotected message containing a writer submessage for the reader \
             EntityId::SEDP_BUILTIN_PUBLICATIONS_READER in an rtps-protected domain."
        ));
        assert!(!is_security_event(
            "rustdds::rtps::writer",
            log::Level::Error,
            "Encoding failed"
        ));
        assert!(!is_security_event(
            "rustdds::discovery::secure_discovery",
            log::Level::Warn,
            "Failed to set remote writer GUID {..} crypto tokens. Storing them & trying again later."
        ));
        assert!(!is_security_event(
            "rustdds::security::security_plugins",
            log::Level::Error,
            "Could not find a remote EndpointCryptoHandle for the (local_endpoint_guid, proxy_guid) pair"
        ));
    }

    #[test]
    fn levels_are_read_and_nonsense_is_named() {
        assert_eq!(dds_log_level(None), Ok(None));
        assert_eq!(dds_log_level(Some(" ")), Ok(None));
        assert_eq!(
            dds_log_level(Some("info")),
            Ok(Some(log::LevelFilter::Info))
        );
        assert_eq!(
            dds_log_level(Some("WARN")),
            Ok(Some(log::LevelFilter::Warn))
        );
        let e = dds_log_level(Some("loud")).unwrap_err();
        assert!(e.contains("'loud'") && e.contains("trace"), "{e}");
    }
}
