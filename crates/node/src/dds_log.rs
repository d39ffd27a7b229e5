//! What the DDS stack itself says, on stderr when asked: RustDDS reports through the `log`
//! facade (lost participants, rediscovery, socket errors), which no node listened to, so a
//! network fault left no trace of what DDS did about it. `METROCELL_DDS_LOG=LEVEL` (error, warn,
//! info, debug, trace; unset = nothing) prints each record at or above LEVEL as
//! `[DDS LEVEL] [seconds.nanos] [target]: message`.

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
