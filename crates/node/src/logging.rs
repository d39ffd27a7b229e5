//! Node logging: each message goes to `/rosout` (rcl_interfaces/Log, via ros2-client) and to
//! stderr in rcl's console format `[LEVEL] [seconds.nanos] [node_name]: message`.

use std::sync::Arc;

use ros2_client::rosout::{NodeLoggingHandle, RosoutRaw};

use crate::ros_args::{LogLevel, RosArgs};

/// Cloneable, thread-safe logger of one node.
#[derive(Clone)]
pub struct Logger {
    inner: Arc<LoggerInner>,
}

struct LoggerInner {
    rosout: Option<NodeLoggingHandle>,
    /// rcl logger name: the node's namespace and name with `.` separators (`cell.tracker`).
    logger_name: String,
    min_level: LogLevel,
    stderr: bool,
}

/// rcl's logger name for a node: fully qualified name without the leading `/`, `/` → `.`.
pub fn logger_name(node_fqn: &str) -> String {
    node_fqn.trim_start_matches('/').replace('/', ".")
}

/// The level a node logs at: the last `--log-level <logger>:=LEVEL` naming this node's logger
/// (`cell.talker`, or the base name), else `--log-level LEVEL`, else INFO.
pub fn effective_log_level(ros: &RosArgs, node_fqn: &str) -> LogLevel {
    let logger = logger_name(node_fqn);
    let base = logger.rsplit('.').next().unwrap_or(&logger).to_string();
    ros.logger_levels
        .iter()
        .rev()
        .find(|(l, _)| *l == logger || *l == base)
        .map(|(_, level)| *level)
        .or(ros.log_level)
        .unwrap_or(LogLevel::Info)
}

/// System clock, nanoseconds since the Unix epoch.
pub fn system_time_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as i64)
        .unwrap_or(0)
}

/// One console line in rcl's default format.
pub fn format_console_line(level: LogLevel, stamp_ns: i64, logger: &str, message: &str) -> String {
    let tag = match level {
        LogLevel::Debug => "DEBUG",
        LogLevel::Info => "INFO",
        LogLevel::Warn => "WARN",
        LogLevel::Error => "ERROR",
        LogLevel::Fatal => "FATAL",
    };
    let secs = stamp_ns.div_euclid(1_000_000_000);
    let nanos = stamp_ns.rem_euclid(1_000_000_000);
    format!("[{tag}] [{secs}.{nanos:09}] [{logger}]: {message}")
}

impl Logger {
    pub(crate) fn new(
        rosout: Option<NodeLoggingHandle>,
        node_fqn: &str,
        min_level: LogLevel,
        stderr: bool,
    ) -> Logger {
        Logger {
            inner: Arc::new(LoggerInner {
                rosout,
                logger_name: logger_name(node_fqn),
                min_level,
                stderr,
            }),
        }
    }

    /// A logger that only prints (for code paths before the node exists).
    pub fn stderr_only(node_fqn: &str, min_level: LogLevel) -> Logger {
        Logger::new(None, node_fqn, min_level, true)
    }

    pub fn log(&self, level: LogLevel, message: &str) {
        if level < self.inner.min_level {
            return;
        }
        let now = system_time_ns();
        if self.inner.stderr {
            eprintln!(
                "{}",
                format_console_line(level, now, &self.inner.logger_name, message)
            );
        }
        if let Some(h) = &self.inner.rosout {
            let ros_level = match level {
                LogLevel::Debug => ros2_client::ros2::LogLevel::Debug,
                LogLevel::Info => ros2_client::ros2::LogLevel::Info,
                LogLevel::Warn => ros2_client::ros2::LogLevel::Warn,
                LogLevel::Error => ros2_client::ros2::LogLevel::Error,
                LogLevel::Fatal => ros2_client::ros2::LogLevel::Fatal,
            };
            h.rosout_raw(
                ros2_client::builtin_interfaces::Time::now(),
                ros_level,
                &self.inner.logger_name,
                message,
                "",
                "",
                0,
            );
        }
    }

    pub fn debug(&self, message: impl AsRef<str>) {
        self.log(LogLevel::Debug, message.as_ref())
    }
    pub fn info(&self, message: impl AsRef<str>) {
        self.log(LogLevel::Info, message.as_ref())
    }
    pub fn warn(&self, message: impl AsRef<str>) {
        self.log(LogLevel::Warn, message.as_ref())
    }
    pub fn error(&self, message: impl AsRef<str>) {
        self.log(LogLevel::Error, message.as_ref())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_level_selection() {
        let ros = |a: &[&str]| {
            crate::ros_args::parse_command_line(a.iter().copied())
                .unwrap()
                .ros
        };
        assert_eq!(
            effective_log_level(&RosArgs::default(), "/cell/talker"),
            LogLevel::Info
        );
        assert_eq!(
            effective_log_level(
                &ros(&["p", "--ros-args", "--log-level", "WARN"]),
                "/cell/talker"
            ),
            LogLevel::Warn
        );
        let r = ros(&[
            "p",
            "--ros-args",
            "--log-level",
            "error",
            "--log-level",
            "cell.talker:=debug",
        ]);
        assert_eq!(effective_log_level(&r, "/cell/talker"), LogLevel::Debug);
        assert_eq!(effective_log_level(&r, "/cell/other"), LogLevel::Error);
    }

    #[test]
    fn console_format_matches_rcl() {
        assert_eq!(logger_name("/cell/tracker"), "cell.tracker");
        assert_eq!(
            format_console_line(LogLevel::Warn, 1_700_000_000_012_345_678, "talker", "hot"),
            "[WARN] [1700000000.012345678] [talker]: hot"
        );
    }
}
