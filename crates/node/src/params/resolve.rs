//! Resolving a node's parameter values from its declarations and the command line, in rcl's
//! precedence order: declared defaults < params files (in command-line order; within a file,
//! later matching sections win) < `-p` overrides (later wins).

use std::collections::BTreeMap;
use std::fmt;
#[cfg(test)]
use std::path::Path;
use std::path::PathBuf;

use super::declaration::{ParamDecl, ValueProblem};
#[cfg(test)]
use super::file::parse_params_file;
use super::file::{pattern_matches_node, read_params_file, ParamsFileError, ParamsFileSection};
use super::value::{ParamKind, ParamType, ParamValue};
use crate::ros_args::RosArgs;

/// Built-in parameter every node has (ROS 2 convention): take time from `/clock`.
pub const USE_SIM_TIME: &str = "use_sim_time";

/// Where a parameter's value came from.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamSource {
    Default,
    File(PathBuf),
    CommandLine,
    /// A `set_parameters` service request (e.g. `ros2 param set`).
    Service,
}

impl fmt::Display for ParamSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamSource::Default => f.write_str("the declared default"),
            ParamSource::File(p) => write!(f, "parameters file '{}'", p.display()),
            ParamSource::CommandLine => f.write_str("the command line (-p)"),
            ParamSource::Service => f.write_str("a set_parameters request"),
        }
    }
}

/// Parameter errors; each names the parameter, what was expected, what was given and where from.
#[derive(Debug, thiserror::Error)]
pub enum ParamError {
    #[error(transparent)]
    File(#[from] ParamsFileError),
    #[error("parameter '{name}' expects a {expected} but {origin} gives {given}")]
    WrongType {
        name: String,
        expected: ParamType,
        given: ParamValue,
        origin: ParamSource,
    },
    #[error("parameter '{name}' must be within [{min}, {max}] but {origin} gives {given}")]
    OutOfRange {
        name: String,
        min: f64,
        max: f64,
        given: ParamValue,
        origin: ParamSource,
    },
    #[error("parameter '{name}' must be one of {allowed} but {origin} gives {given}")]
    NotAllowed {
        name: String,
        allowed: String,
        given: ParamValue,
        origin: ParamSource,
    },
    #[error("parameter '{name}' is declared twice")]
    DeclaredTwice { name: String },
    #[error("parameter '{name}' is not declared by this node")]
    NotDeclared { name: String },
    #[error("parameter '{name}' is a {actual}, not a {requested}")]
    TypeMismatch {
        name: String,
        actual: ParamType,
        requested: ParamType,
    },
}

/// One resolved parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedParam {
    pub decl: ParamDecl,
    pub value: ParamValue,
    pub source: ParamSource,
}

/// The node's parameters after resolution, plus warnings (unknown parameters given).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Parameters {
    params: BTreeMap<String, ResolvedParam>,
    warnings: Vec<String>,
}

/// A candidate value for a parameter from one source.
struct Candidate<'a> {
    name: &'a str,
    value: &'a ParamValue,
    source: ParamSource,
}

impl Parameters {
    /// Resolve from the declarations and the ROS arguments (reads the params files).
    /// `node_fqn` is the node's fully qualified name (`/ns/name`) and `node_base` its base name,
    /// used to select params-file sections and node-targeted `-p node:name:=v` overrides.
    pub fn resolve(
        decls: &[ParamDecl],
        ros: &RosArgs,
        node_fqn: &str,
        node_base: &str,
    ) -> Result<Parameters, ParamError> {
        let files = ros
            .params_files
            .iter()
            .map(|p| Ok((p.clone(), read_params_file(p)?)))
            .collect::<Result<Vec<_>, ParamsFileError>>()?;
        Parameters::resolve_from(decls, &files, ros, node_fqn, node_base)
    }

    /// Resolve from already-parsed params files (pure; what [`Parameters::resolve`] calls).
    pub fn resolve_from(
        decls: &[ParamDecl],
        files: &[(PathBuf, Vec<ParamsFileSection>)],
        ros: &RosArgs,
        node_fqn: &str,
        node_base: &str,
    ) -> Result<Parameters, ParamError> {
        let mut all: Vec<ParamDecl> = decls.to_vec();
        if !all.iter().any(|d| d.name == USE_SIM_TIME) {
            all.push(ParamDecl::new(
                USE_SIM_TIME,
                false,
                "take time from /clock instead of the system clock",
            ));
        }
        let mut params = BTreeMap::new();
        for d in all {
            let value = d
                .check(&d.default)
                .map_err(|p| problem_error(&d, &d.default, ParamSource::Default, p))?;
            let name = d.name.clone();
            if params
                .insert(
                    name.clone(),
                    ResolvedParam {
                        decl: d,
                        value,
                        source: ParamSource::Default,
                    },
                )
                .is_some()
            {
                return Err(ParamError::DeclaredTwice { name });
            }
        }
        let mut out = Parameters {
            params,
            warnings: Vec::new(),
        };

        let mut candidates = Vec::new();
        for (path, sections) in files {
            for section in sections
                .iter()
                .filter(|s| pattern_matches_node(&s.node_pattern, node_fqn))
            {
                for (name, value) in &section.params {
                    candidates.push(Candidate {
                        name,
                        value,
                        source: ParamSource::File(path.clone()),
                    });
                }
            }
        }
        for o in ros
            .param_overrides
            .iter()
            .filter(|o| o.node.as_deref().is_none_or(|n| n == node_base))
        {
            candidates.push(Candidate {
                name: &o.name,
                value: &o.value,
                source: ParamSource::CommandLine,
            });
        }
        for c in candidates {
            out.apply(c)?;
        }
        Ok(out)
    }

    fn apply(&mut self, c: Candidate<'_>) -> Result<(), ParamError> {
        let Some(slot) = self.params.get_mut(c.name) else {
            let w = format!(
                "parameter '{}' from {} is not declared by this node; ignored",
                c.name, c.source
            );
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
            return Ok(());
        };
        let value = slot
            .decl
            .check(c.value)
            .map_err(|p| problem_error(&slot.decl, c.value, c.source.clone(), p))?;
        slot.value = value;
        slot.source = c.source;
        Ok(())
    }

    /// Value of a declared parameter as `T`.
    pub fn get<T: ParamKind>(&self, name: &str) -> Result<T, ParamError> {
        let p = self
            .params
            .get(name)
            .ok_or_else(|| ParamError::NotDeclared {
                name: name.to_string(),
            })?;
        T::from_value(&p.value).ok_or(ParamError::TypeMismatch {
            name: name.to_string(),
            actual: p.value.param_type(),
            requested: T::TYPE,
        })
    }

    pub fn value(&self, name: &str) -> Option<&ParamValue> {
        self.params.get(name).map(|p| &p.value)
    }

    pub fn resolved(&self, name: &str) -> Option<&ResolvedParam> {
        self.params.get(name)
    }

    /// All parameters, sorted by name.
    pub fn iter(&self) -> impl Iterator<Item = &ResolvedParam> {
        self.params.values()
    }

    /// Replace a value at run time (e.g. a remote `ros2 param set`), checked against the declaration.
    pub fn set(
        &mut self,
        name: &str,
        value: &ParamValue,
        source: ParamSource,
    ) -> Result<(), ParamError> {
        if !self.params.contains_key(name) {
            return Err(ParamError::NotDeclared {
                name: name.to_string(),
            });
        }
        self.apply(Candidate {
            name,
            value,
            source,
        })
    }

    /// Warnings produced while resolving (parameters given but not declared).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

pub(crate) fn problem_error(
    decl: &ParamDecl,
    given: &ParamValue,
    source: ParamSource,
    problem: ValueProblem,
) -> ParamError {
    let name = decl.name.clone();
    let given = given.clone();
    match problem {
        ValueProblem::WrongType { expected } => ParamError::WrongType {
            name,
            expected,
            given,
            origin: source,
        },
        ValueProblem::OutOfRange { min, max } => ParamError::OutOfRange {
            name,
            min,
            max,
            given,
            origin: source,
        },
        ValueProblem::NotAllowed { allowed } => ParamError::NotAllowed {
            name,
            allowed: format!(
                "[{}]",
                allowed
                    .iter()
                    .map(|a| a.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            given,
            origin: source,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros_args::parse_command_line;

    fn decls() -> Vec<ParamDecl> {
        vec![
            ParamDecl::new("rate_hz", 10.0, "rate").with_range(0.1, 1000.0),
            ParamDecl::new("topic", "chatter", "topic"),
            ParamDecl::new("count", 3i64, "count"),
            ParamDecl::new("tracker.port", 4000i64, "port"),
        ]
    }

    fn files() -> Vec<(PathBuf, Vec<ParamsFileSection>)> {
        let a = "/**:\n  ros__parameters:\n    rate_hz: 20.0\n    topic: from_a\n    count: 7\n";
        let b = "talker:\n  ros__parameters:\n    rate_hz: 30\n    tracker:\n      port: 5000\n    bogus: 1\n/other:\n  ros__parameters:\n    count: 99\n";
        vec![
            (
                PathBuf::from("a.yaml"),
                parse_params_file(a, Path::new("a.yaml")).unwrap(),
            ),
            (
                PathBuf::from("b.yaml"),
                parse_params_file(b, Path::new("b.yaml")).unwrap(),
            ),
        ]
    }

    #[test]
    fn precedence_defaults_files_overrides() {
        let ros = parse_command_line([
            "p",
            "--ros-args",
            "-p",
            "topic:=cli",
            "-p",
            "other:count:=5",
        ])
        .unwrap()
        .ros;
        let p = Parameters::resolve_from(&decls(), &files(), &ros, "/talker", "talker").unwrap();
        assert_eq!(p.get::<f64>("rate_hz").unwrap(), 30.0); // b.yaml (later file) beats a.yaml
        assert_eq!(
            p.resolved("rate_hz").unwrap().source,
            ParamSource::File("b.yaml".into())
        );
        assert_eq!(p.get::<String>("topic").unwrap(), "cli"); // -p beats files
        assert_eq!(
            p.resolved("topic").unwrap().source,
            ParamSource::CommandLine
        );
        assert_eq!(p.get::<i64>("count").unwrap(), 7); // /other section and other:count do not apply
        assert_eq!(p.get::<i64>("tracker.port").unwrap(), 5000);
        assert!(!p.get::<bool>("use_sim_time").unwrap());
        assert_eq!(p.warnings().len(), 1);
        assert!(
            p.warnings()[0].contains("bogus") && p.warnings()[0].contains("b.yaml"),
            "{:?}",
            p.warnings()
        );
    }

    #[test]
    fn defaults_when_nothing_given() {
        let p = Parameters::resolve_from(&decls(), &[], &RosArgs::default(), "/x", "x").unwrap();
        assert_eq!(p.get::<f64>("rate_hz").unwrap(), 10.0);
        assert_eq!(p.resolved("rate_hz").unwrap().source, ParamSource::Default);
        assert!(matches!(
            p.get::<i64>("rate_hz"),
            Err(ParamError::TypeMismatch { .. })
        ));
        assert!(matches!(
            p.get::<i64>("nope"),
            Err(ParamError::NotDeclared { .. })
        ));
    }

    #[test]
    fn wrong_type_names_parameter_and_source() {
        let ros = parse_command_line(["p", "--ros-args", "-p", "count:=abc"])
            .unwrap()
            .ros;
        let e = Parameters::resolve_from(&decls(), &[], &ros, "/x", "x").unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("'count'")
                && m.contains("integer")
                && m.contains("\"abc\"")
                && m.contains("command line"),
            "{m}"
        );
        let bad = "/**:\n  ros__parameters:\n    topic: [1, 2]\n";
        let f = vec![(
            PathBuf::from("cfg/bad.yaml"),
            parse_params_file(bad, Path::new("cfg/bad.yaml")).unwrap(),
        )];
        let m = Parameters::resolve_from(&decls(), &f, &RosArgs::default(), "/x", "x")
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("'topic'") && m.contains("string") && m.contains("cfg/bad.yaml"),
            "{m}"
        );
    }

    #[test]
    fn out_of_range_names_range_and_value() {
        let ros = parse_command_line(["p", "--ros-args", "-p", "rate_hz:=5000"])
            .unwrap()
            .ros;
        let m = Parameters::resolve_from(&decls(), &[], &ros, "/x", "x")
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("'rate_hz'") && m.contains("[0.1, 1000]") && m.contains("5000"),
            "{m}"
        );
    }

    #[test]
    fn missing_params_file_is_an_error_naming_it() {
        let ros = parse_command_line(["p", "--ros-args", "--params-file", "/no/such/file.yaml"])
            .unwrap()
            .ros;
        let m = Parameters::resolve(&decls(), &ros, "/x", "x")
            .unwrap_err()
            .to_string();
        assert!(m.contains("/no/such/file.yaml"), "{m}");
    }
}
