//! The ROS 2 command line (rcl rules): `--ros-args ... [--]` may appear anywhere, several times;
//! everything outside those sections belongs to the node itself.
//!
//! Inside a section: `-r/--remap [node:]from:=to` (including `__node:=`/`__name:=` and `__ns:=`),
//! `-p/--param [node:]name:=value` (value read with YAML rules), `--params-file FILE`,
//! `--log-level [logger:=]LEVEL`, `-e/--enclave X` (accepted, ignored), and the rcl logging
//! switches (`--enable-/--disable-rosout-logs`, `...-stdout-logs`, `...-external-lib-logs`,
//! `--log-config-file FILE`), accepted and ignored except where noted.

use std::path::PathBuf;

use crate::params::ParamValue;

/// A remap rule `[node:]from:=to`.
#[derive(Clone, Debug, PartialEq)]
pub struct Remap {
    /// If set, the rule applies only to the node with this (base) name.
    pub node: Option<String>,
    pub from: String,
    pub to: String,
}

/// A parameter override `-p [node:]name:=value`.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamOverride {
    /// If set, the override applies only to the node with this (base) name.
    pub node: Option<String>,
    pub name: String,
    pub value: ParamValue,
}

/// Log severity from `--log-level`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    Debug,
    Info,
    Warn,
    Error,
    Fatal,
}

impl LogLevel {
    pub fn parse(text: &str) -> Option<LogLevel> {
        Some(match text.to_ascii_lowercase().as_str() {
            "debug" => LogLevel::Debug,
            "info" => LogLevel::Info,
            "warn" | "warning" => LogLevel::Warn,
            "error" => LogLevel::Error,
            "fatal" => LogLevel::Fatal,
            _ => return None,
        })
    }
}

/// Everything the ROS sections of a command line said.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RosArgs {
    pub remaps: Vec<Remap>,
    pub param_overrides: Vec<ParamOverride>,
    /// In command-line order (later files override earlier ones).
    pub params_files: Vec<PathBuf>,
    /// `--log-level LEVEL` (the default logger's level; `name:=LEVEL` forms are kept separately).
    pub log_level: Option<LogLevel>,
    pub logger_levels: Vec<(String, LogLevel)>,
    pub enclave: Option<String>,
    /// `--disable-rosout-logs` was given.
    pub disable_rosout: bool,
    /// `--disable-stdout-logs` was given.
    pub disable_stdout: bool,
}

impl RosArgs {
    /// Node name from `[node:]__node:=` / `__name:=` remaps (last wins), if any apply to `original`.
    pub fn node_name_remap(&self, original: &str) -> Option<String> {
        self.special_remap(original, &["__node", "__name"])
    }

    /// Namespace from `[node:]__ns:=` remaps (last wins), if any apply to `original`.
    pub fn namespace_remap(&self, original: &str) -> Option<String> {
        self.special_remap(original, &["__ns"])
    }

    fn special_remap(&self, original: &str, keys: &[&str]) -> Option<String> {
        self.remaps
            .iter()
            .rfind(|r| {
                keys.contains(&r.from.as_str()) && r.node.as_deref().is_none_or(|n| n == original)
            })
            .map(|r| r.to.clone())
    }
}

/// The split command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CommandLine {
    pub ros: RosArgs,
    /// The node's own arguments, in order, with program name (argv[0]) kept first if it was given,
    /// so they can go straight to e.g. `clap::Parser::parse_from`.
    pub node_args: Vec<String>,
}

/// A bad ROS argument; the message names it.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RosArgsError {
    #[error("ROS argument '{flag}' needs a value after it")]
    MissingValue { flag: String },
    #[error("ROS argument '{flag} {value}': expected the form {expected}")]
    BadForm {
        flag: String,
        value: String,
        expected: &'static str,
    },
    #[error("ROS argument '{flag} {value}': {message}")]
    BadValue {
        flag: String,
        value: String,
        message: String,
    },
    #[error("unknown ROS argument '{arg}' (after --ros-args; end the ROS section with '--' before the node's own arguments)")]
    Unknown { arg: String },
}

/// Parse a full argv (`std::env::args()`), argv[0] included.
pub fn parse_command_line<I, S>(argv: I) -> Result<CommandLine, RosArgsError>
where
    I: IntoIterator<Item = S>,
    S: Into<String>,
{
    let args: Vec<String> = argv.into_iter().map(Into::into).collect();
    let mut out = CommandLine::default();
    let mut i = 0;
    let mut in_ros = false;
    while i < args.len() {
        let arg = &args[i];
        if !in_ros {
            if arg == "--ros-args" {
                in_ros = true;
            } else {
                out.node_args.push(arg.clone());
            }
            i += 1;
            continue;
        }
        // Inside a ROS section.
        let mut value = |flag: &str| -> Result<String, RosArgsError> {
            i += 1;
            args.get(i).cloned().ok_or(RosArgsError::MissingValue {
                flag: flag.to_string(),
            })
        };
        match arg.as_str() {
            "--" => in_ros = false,
            "--ros-args" => {}
            "-r" | "--remap" => {
                let v = value(arg)?;
                out.ros.remaps.push(parse_remap(arg, &v)?);
            }
            "-p" | "--param" => {
                let v = value(arg)?;
                out.ros.param_overrides.push(parse_param(arg, &v)?);
            }
            "--params-file" => {
                let v = value(arg)?;
                out.ros.params_files.push(PathBuf::from(v));
            }
            "--log-level" => {
                let v = value(arg)?;
                parse_log_level(arg, &v, &mut out.ros)?;
            }
            "-e" | "--enclave" => {
                let v = value(arg)?;
                out.ros.enclave = Some(v);
            }
            "--log-config-file" => {
                value(arg)?;
            }
            "--disable-rosout-logs" => out.ros.disable_rosout = true,
            "--enable-rosout-logs" => out.ros.disable_rosout = false,
            "--disable-stdout-logs" => out.ros.disable_stdout = true,
            "--enable-stdout-logs" => out.ros.disable_stdout = false,
            "--disable-external-lib-logs" | "--enable-external-lib-logs" => {}
            other => {
                return Err(RosArgsError::Unknown {
                    arg: other.to_string(),
                })
            }
        }
        i += 1;
    }
    Ok(out)
}

/// Split `[node:]left:=right`. The node prefix is the part before a single `:` that is not part of `:=`.
fn split_assignment(text: &str) -> Option<(Option<String>, String, String)> {
    let (lhs, rhs) = text.split_once(":=")?;
    let (node, key) = match lhs.split_once(':') {
        Some((node, key)) => (Some(node.to_string()), key.to_string()),
        None => (None, lhs.to_string()),
    };
    if key.is_empty() || node.as_deref() == Some("") {
        return None;
    }
    Some((node, key, rhs.to_string()))
}

fn parse_remap(flag: &str, text: &str) -> Result<Remap, RosArgsError> {
    let (node, from, to) = split_assignment(text).ok_or(RosArgsError::BadForm {
        flag: flag.to_string(),
        value: text.to_string(),
        expected: "[node:]from:=to",
    })?;
    if to.is_empty() {
        return Err(RosArgsError::BadValue {
            flag: flag.to_string(),
            value: text.to_string(),
            message: "the replacement name is empty".to_string(),
        });
    }
    Ok(Remap { node, from, to })
}

fn parse_param(flag: &str, text: &str) -> Result<ParamOverride, RosArgsError> {
    let (node, name, value_text) = split_assignment(text).ok_or(RosArgsError::BadForm {
        flag: flag.to_string(),
        value: text.to_string(),
        expected: "[node:]name:=value",
    })?;
    let value =
        ParamValue::parse_yaml_text(&value_text).map_err(|message| RosArgsError::BadValue {
            flag: flag.to_string(),
            value: text.to_string(),
            message,
        })?;
    Ok(ParamOverride { node, name, value })
}

fn parse_log_level(flag: &str, text: &str, ros: &mut RosArgs) -> Result<(), RosArgsError> {
    let bad = || RosArgsError::BadValue {
        flag: flag.to_string(),
        value: text.to_string(),
        message: "log level must be one of debug, info, warn, error, fatal".to_string(),
    };
    match text.split_once(":=") {
        Some((logger, level)) => {
            let level = LogLevel::parse(level).ok_or_else(bad)?;
            ros.logger_levels.push((logger.to_string(), level));
        }
        None => ros.log_level = Some(LogLevel::parse(text).ok_or_else(bad)?),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn argv(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn ros_sections_are_split_from_node_args() {
        let c = parse_command_line(argv(
            "prog --verbose --ros-args -r chatter:=/talk -p rate:=2.5 --params-file a.yaml -- input.bag --ros-args --log-level warn",
        ))
        .unwrap();
        assert_eq!(c.node_args, argv("prog --verbose input.bag"));
        assert_eq!(
            c.ros.remaps,
            vec![Remap {
                node: None,
                from: "chatter".into(),
                to: "/talk".into()
            }]
        );
        assert_eq!(
            c.ros.param_overrides,
            vec![ParamOverride {
                node: None,
                name: "rate".into(),
                value: ParamValue::Double(2.5)
            }]
        );
        assert_eq!(c.ros.params_files, vec![PathBuf::from("a.yaml")]);
        assert_eq!(c.ros.log_level, Some(LogLevel::Warn));
    }

    #[test]
    fn node_targeted_and_special_remaps() {
        let c = parse_command_line(argv(
            "p --ros-args -r __node:=cam2 -r __ns:=/cell -r probe:image:=/cam/image -p probe:gain:=[1,2] -e /x --remap talker:__node:=t2",
        ))
        .unwrap();
        assert_eq!(
            c.ros.remaps[2],
            Remap {
                node: Some("probe".into()),
                from: "image".into(),
                to: "/cam/image".into()
            }
        );
        assert_eq!(c.ros.param_overrides[0].node.as_deref(), Some("probe"));
        assert_eq!(
            c.ros.param_overrides[0].value,
            ParamValue::IntegerArray(vec![1, 2])
        );
        assert_eq!(c.ros.node_name_remap("probe").as_deref(), Some("cam2"));
        assert_eq!(c.ros.node_name_remap("talker").as_deref(), Some("t2"));
        assert_eq!(c.ros.namespace_remap("x").as_deref(), Some("/cell"));
        assert_eq!(c.ros.enclave.as_deref(), Some("/x"));
    }

    #[test]
    fn param_values_with_colons_and_types() {
        let c = parse_command_line(argv(
            "p --ros-args -p url:=http://h:80 -p on:=true -p n:=3 -p s:=abc",
        ))
        .unwrap();
        let v: Vec<_> = c
            .ros
            .param_overrides
            .iter()
            .map(|p| (p.name.as_str(), p.value.clone()))
            .collect();
        assert_eq!(v[0], ("url", ParamValue::String("http://h:80".into())));
        assert_eq!(v[1], ("on", ParamValue::Bool(true)));
        assert_eq!(v[2], ("n", ParamValue::Integer(3)));
        assert_eq!(v[3], ("s", ParamValue::String("abc".into())));
    }

    #[test]
    fn errors_name_the_argument() {
        let e = parse_command_line(argv("p --ros-args -p rate=3")).unwrap_err();
        assert!(e.to_string().contains("-p rate=3"), "{e}");
        let e = parse_command_line(argv("p --ros-args -r")).unwrap_err();
        assert_eq!(e, RosArgsError::MissingValue { flag: "-r".into() });
        let e = parse_command_line(argv("p --ros-args --frobnicate")).unwrap_err();
        assert!(e.to_string().contains("--frobnicate"), "{e}");
        let e = parse_command_line(argv("p --ros-args --log-level loud")).unwrap_err();
        assert!(e.to_string().contains("loud"), "{e}");
        let e = parse_command_line(argv("p --ros-args -r a:=")).unwrap_err();
        assert!(e.to_string().contains("a:="), "{e}");
    }

    #[test]
    fn no_ros_args_leaves_everything_to_the_node() {
        let c = parse_command_line(argv("p -r x:=y")).unwrap();
        assert_eq!(c.node_args, argv("p -r x:=y"));
        assert_eq!(c.ros, RosArgs::default());
    }
}
