//! Reading ROS 2 YAML launch files into a [`LaunchPlan`].
//!
//! The format is the one of ROS 2's `launch_yaml`/`launch_ros` frontends: a top-level `launch:`
//! list whose items are one-key mappings naming an action:
//!
//! | action | keys |
//! |---|---|
//! | `arg` | `name` (required), `default`, `description` |
//! | `let` | `name`, `value` (both required) |
//! | `include` | `file` (required), `arg`: list of `{name, value}`; or just `include: FILE` |
//! | `node` | `exec` (required), `pkg`, `name`, `namespace`, `param`, `remap`, `args`, `ros_args`, `enclave`, `respawn`, `respawn_delay`, `respawn_max_retries`, `output`, `env` |
//! | `executable` | `cmd` (required), `name`, `args`, `cwd`, `shell`, `respawn`, `respawn_delay`, `respawn_max_retries`, `output`, `env` |
//! | `group` | `scoped` (default true), `forwarding` (default true), `push-ros-namespace`/`push_ros_namespace`, `children`; or a plain list of child actions |
//! | `push-ros-namespace` / `push_ros_namespace` | `namespace`; or just `push-ros-namespace: NS` |
//!
//! Every action also takes `if` / `unless` (a `true`/`false` text after substitution).
//! `param` items are `{name, value}`, `{from: PARAMS_FILE}` or `{name, param: [...]}` (nested
//! names joined with `.`); `remap` items are `{from, to}`; `env` items are `{name, value}`.
//!
//! Scoping, as in ROS 2 launch: launch configurations (`arg`, `let`) and the pushed namespace set
//! inside a scoped group or an included file are not seen after it; an included file sees the
//! includer's configurations plus its `arg` list. `name:=value` given on the command line is set
//! before anything is read, so it overrides every `arg` default of that name in every file.
//! Relative paths in `include.file` and `param.from` are looked up next to the file that names
//! them first, then in the working directory.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::command_line::{
    combine_namespace, default_search_path, resolve_executable, ros_args, shell_split,
    yaml_single_quote, yaml_string_needs_quotes, ParamArg,
};
use crate::error::LaunchError;
use crate::marked_yaml::{parse_marked_yaml, MarkedNode, MarkedValue};
use crate::options::LaunchOptions;
use crate::plan::{DeclaredArgument, LaunchPlan, OutputMode, ProcessSpec};
use crate::substitution::{substitute, SubstitutionScope};

const ACTIONS: &str = "arg, let, include, node, executable, group, push-ros-namespace";
const NODE_KEYS: &[&str] = &[
    "pkg",
    "exec",
    "name",
    "namespace",
    "param",
    "remap",
    "args",
    "ros_args",
    "enclave",
    "respawn",
    "respawn_delay",
    "respawn_max_retries",
    "output",
    "env",
];
const EXECUTABLE_KEYS: &[&str] = &[
    "cmd",
    "name",
    "args",
    "cwd",
    "shell",
    "respawn",
    "respawn_delay",
    "respawn_max_retries",
    "output",
    "env",
];
const GROUP_KEYS: &[&str] = &[
    "scoped",
    "forwarding",
    "push-ros-namespace",
    "push_ros_namespace",
    "children",
];
const CONDITION_KEYS: &[&str] = &["if", "unless"];

/// Reads `path` (and everything it includes) with the command-line launch arguments `args`
/// (`(name, value)` pairs, from `name:=value`) and resolves it into processes. Starts nothing.
pub fn load_launch_plan(
    path: &Path,
    args: &[(String, String)],
    options: &LaunchOptions,
) -> Result<LaunchPlan, LaunchError> {
    let mut loader = Loader {
        options,
        search: options
            .executable_search_path
            .clone()
            .unwrap_or_else(default_search_path),
        include_stack: Vec::new(),
        plan: LaunchPlan {
            processes: Vec::new(),
            arguments: Vec::new(),
        },
        declared: BTreeSet::new(),
    };
    let mut scope = Scope {
        vars: args.iter().cloned().collect(),
        namespace: None,
    };
    loader.load_file(path, &mut scope)?;
    for (name, _) in args {
        if !loader.declared.contains(name) {
            let declared: Vec<&str> = loader.declared.iter().map(String::as_str).collect();
            return Err(LaunchError::UndeclaredArgument {
                name: name.clone(),
                declared: if declared.is_empty() {
                    "none".into()
                } else {
                    declared.join(", ")
                },
            });
        }
    }
    make_labels_unique(&mut loader.plan.processes);
    Ok(loader.plan)
}

/// Splits command-line items `name:=value` into pairs.
pub fn parse_launch_arguments<S: AsRef<str>>(
    items: &[S],
) -> Result<Vec<(String, String)>, LaunchError> {
    items
        .iter()
        .map(|item| {
            let item = item.as_ref();
            match item.split_once(":=") {
                Some((name, value)) if !name.is_empty() => {
                    Ok((name.to_string(), value.to_string()))
                }
                _ => Err(LaunchError::BadArgumentSyntax {
                    given: item.to_string(),
                }),
            }
        })
        .collect()
}

/// What is in force at a point of a launch file.
#[derive(Clone, Debug)]
struct Scope {
    /// Launch configurations: values of `arg` and `let`.
    vars: BTreeMap<String, String>,
    /// Namespace pushed by `push-ros-namespace`, normalized (`/a/b`).
    namespace: Option<String>,
}

struct Loader<'o> {
    options: &'o LaunchOptions,
    search: Vec<PathBuf>,
    /// Canonical paths of the files being read, outermost first (include cycle detection).
    include_stack: Vec<PathBuf>,
    plan: LaunchPlan,
    declared: BTreeSet<String>,
}

/// The keys of one action (or list item) mapping, checked against what is allowed there.
struct Body<'n> {
    file: &'n Path,
    /// Key path for messages, e.g. `node` or `node.param[2]`.
    context: String,
    line: usize,
    entries: &'n [(MarkedNode, MarkedNode)],
}

impl<'n> Body<'n> {
    /// `node` must be a mapping (or empty) whose keys are all in `allowed` (plus `if`/`unless`
    /// when `conditions`).
    fn new(
        file: &'n Path,
        context: String,
        line: usize,
        node: &'n MarkedNode,
        allowed: &[&str],
        conditions: bool,
    ) -> Result<Self, LaunchError> {
        let entries: &[(MarkedNode, MarkedNode)] = match &node.value {
            MarkedValue::Mapping(entries) => entries,
            _ if node.is_null() => &[],
            _ => {
                return Err(LaunchError::invalid(
                    file,
                    node.line,
                    context,
                    format!("expected a mapping of keys, found {}", node.kind_name()),
                ))
            }
        };
        for (key, _) in entries {
            let name = key.as_scalar().unwrap_or("");
            let ok = allowed.contains(&name) || (conditions && CONDITION_KEYS.contains(&name));
            if !ok {
                let mut expected = allowed.to_vec();
                if conditions {
                    expected.extend_from_slice(CONDITION_KEYS);
                }
                let shown = key
                    .as_scalar()
                    .map(|k| format!("'{k}'"))
                    .unwrap_or_else(|| key.kind_name().to_string());
                return Err(LaunchError::invalid(
                    file,
                    key.line,
                    context,
                    format!(
                        "unknown key {shown} (expected one of {})",
                        expected.join(", ")
                    ),
                ));
            }
        }
        Ok(Body {
            file,
            context,
            line,
            entries,
        })
    }

    fn entry(&self, key: &str) -> Option<&'n (MarkedNode, MarkedNode)> {
        self.entries
            .iter()
            .find(|(k, _)| k.as_scalar() == Some(key))
    }

    fn get(&self, key: &str) -> Option<&'n MarkedNode> {
        self.entry(key).map(|(_, v)| v)
    }

    fn key_path(&self, key: &str) -> String {
        format!("{}.{key}", self.context)
    }

    fn error_at(&self, key: &str, message: impl Into<String>) -> LaunchError {
        let line = self.entry(key).map(|(k, _)| k.line).unwrap_or(self.line);
        LaunchError::invalid(self.file, line, self.key_path(key), message)
    }

    fn missing(&self, key: &str) -> LaunchError {
        LaunchError::invalid(
            self.file,
            self.line,
            self.context.clone(),
            format!("missing required key '{key}'"),
        )
    }

    /// The list under `key`; absent or null = empty.
    fn list(&self, key: &str) -> Result<&'n [MarkedNode], LaunchError> {
        match self.get(key) {
            None => Ok(&[]),
            Some(v) if v.is_null() => Ok(&[]),
            Some(MarkedNode {
                value: MarkedValue::Sequence(items),
                ..
            }) => Ok(items),
            Some(other) => {
                Err(self.error_at(key, format!("expected a list, found {}", other.kind_name())))
            }
        }
    }
}

impl<'o> Loader<'o> {
    fn load_file(&mut self, path: &Path, scope: &mut Scope) -> Result<(), LaunchError> {
        let text = std::fs::read_to_string(path).map_err(|source| LaunchError::Read {
            file: path.to_path_buf(),
            source,
        })?;
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        self.include_stack.push(canonical);
        let root = parse_marked_yaml(&text).map_err(|e| LaunchError::YamlSyntax {
            file: path.to_path_buf(),
            line: e.line,
            column: e.column,
            message: e.message,
        })?;
        let Some(root) = root else {
            return Err(LaunchError::invalid(
                path,
                1,
                "launch",
                "empty launch file (expected a top-level 'launch:' list)",
            ));
        };
        let body = Body::new(
            path,
            "(top level)".into(),
            root.line,
            &root,
            &["launch"],
            false,
        )?;
        let Some(actions) = body.get("launch") else {
            return Err(LaunchError::invalid(
                path,
                root.line,
                "(top level)",
                "missing required key 'launch'",
            ));
        };
        match &actions.value {
            MarkedValue::Sequence(items) => self.run_actions(path, items, scope)?,
            _ if actions.is_null() => {}
            _ => {
                return Err(LaunchError::invalid(
                    path,
                    actions.line,
                    "launch",
                    format!("expected a list of actions, found {}", actions.kind_name()),
                ))
            }
        }
        self.include_stack.pop();
        Ok(())
    }

    fn run_actions(
        &mut self,
        file: &Path,
        items: &[MarkedNode],
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        for item in items {
            self.action(file, item, scope)?;
        }
        Ok(())
    }

    fn action(
        &mut self,
        file: &Path,
        item: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        let (key, body) = match &item.value {
            MarkedValue::Mapping(entries) if entries.len() == 1 => (&entries[0].0, &entries[0].1),
            MarkedValue::Mapping(entries) => {
                let keys: Vec<&str> = entries.iter().filter_map(|(k, _)| k.as_scalar()).collect();
                return Err(LaunchError::invalid(
                    file,
                    item.line,
                    "launch",
                    format!(
                        "an action is a mapping with exactly one key, the action name (found keys: {}); \
                         indent the action's keys under it",
                        keys.join(", ")
                    ),
                ));
            }
            _ => {
                return Err(LaunchError::invalid(
                    file,
                    item.line,
                    "launch",
                    format!(
                        "expected an action such as '- node: ...', found {}",
                        item.kind_name()
                    ),
                ))
            }
        };
        let name = key.as_scalar().unwrap_or("");
        let line = key.line;
        if !self.condition_holds(file, name, line, body, scope)? {
            return Ok(());
        }
        match name {
            "arg" => self.arg(file, line, body, scope),
            "let" => self.let_(file, line, body, scope),
            "include" => self.include(file, line, body, scope),
            "node" => self.node(file, line, body, scope),
            "executable" => self.executable(file, line, body, scope),
            "group" => self.group(file, line, body, scope),
            "push-ros-namespace" | "push_ros_namespace" => {
                self.push_namespace(file, line, name, body, scope)
            }
            other => Err(LaunchError::invalid(
                file,
                line,
                "launch",
                format!("unknown action '{other}' (expected one of {ACTIONS})"),
            )),
        }
    }

    /// `if:` / `unless:` of an action (only looked at when the action body is a mapping).
    fn condition_holds(
        &self,
        file: &Path,
        action: &str,
        line: usize,
        body: &MarkedNode,
        scope: &Scope,
    ) -> Result<bool, LaunchError> {
        let MarkedValue::Mapping(entries) = &body.value else {
            return Ok(true);
        };
        for (key, value) in entries {
            let negate = match key.as_scalar() {
                Some("if") => false,
                Some("unless") => true,
                _ => continue,
            };
            let ctx = format!("{action}.{}", key.as_scalar().unwrap_or(""));
            let flag = self.bool_value(file, key.line.max(line), &ctx, value, scope)?;
            if flag == negate {
                return Ok(false);
            }
        }
        Ok(true)
    }

    // ---- values -------------------------------------------------------------------------

    fn subst(
        &self,
        file: &Path,
        line: usize,
        key: &str,
        text: &str,
        scope: &Scope,
    ) -> Result<String, LaunchError> {
        let env = |name: &str| self.options.env_var(name);
        let share = |pkg: &str| self.find_pkg_share(file, pkg);
        let sub_scope = SubstitutionScope {
            vars: &scope.vars,
            env: &env,
            current_file: file,
            find_pkg_share: &share,
        };
        substitute(text, &sub_scope).map_err(|m| LaunchError::invalid(file, line, key, m))
    }

    /// A scalar value after substitution; null gives `None`.
    fn text_value(
        &self,
        file: &Path,
        key: &str,
        node: &MarkedNode,
        scope: &Scope,
    ) -> Result<Option<String>, LaunchError> {
        match &node.value {
            _ if node.is_null() => Ok(None),
            MarkedValue::Scalar { text, .. } => {
                self.subst(file, node.line, key, text, scope).map(Some)
            }
            _ => Err(LaunchError::invalid(
                file,
                node.line,
                key,
                format!("expected a text value, found {}", node.kind_name()),
            )),
        }
    }

    fn text(&self, body: &Body, key: &str, scope: &Scope) -> Result<Option<String>, LaunchError> {
        match body.get(key) {
            None => Ok(None),
            Some(node) => self.text_value(body.file, &body.key_path(key), node, scope),
        }
    }

    fn required_text(&self, body: &Body, key: &str, scope: &Scope) -> Result<String, LaunchError> {
        match self.text(body, key, scope)? {
            Some(v) if !v.is_empty() => Ok(v),
            Some(_) => Err(body.error_at(key, "must not be empty")),
            None if body.get(key).is_some() => Err(body.error_at(key, "must not be empty")),
            None => Err(body.missing(key)),
        }
    }

    fn bool_value(
        &self,
        file: &Path,
        line: usize,
        key: &str,
        node: &MarkedNode,
        scope: &Scope,
    ) -> Result<bool, LaunchError> {
        let text = self.text_value(file, key, node, scope)?.unwrap_or_default();
        match text.to_ascii_lowercase().as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(LaunchError::invalid(
                file,
                line,
                key,
                format!("expected true or false, found '{text}'"),
            )),
        }
    }

    fn bool(&self, body: &Body, key: &str, scope: &Scope) -> Result<Option<bool>, LaunchError> {
        let Some((k, node)) = body.entry(key) else {
            return Ok(None);
        };
        self.bool_value(body.file, k.line, &body.key_path(key), node, scope)
            .map(Some)
    }

    fn seconds(
        &self,
        body: &Body,
        key: &str,
        scope: &Scope,
    ) -> Result<Option<Duration>, LaunchError> {
        let Some(text) = self.text(body, key, scope)? else {
            return Ok(None);
        };
        match text.trim().parse::<f64>() {
            Ok(s) if s.is_finite() && s >= 0.0 => Ok(Some(Duration::from_secs_f64(s))),
            _ => Err(body.error_at(
                key,
                format!("expected a non-negative number of seconds, found '{text}'"),
            )),
        }
    }

    // ---- actions ------------------------------------------------------------------------

    fn arg(
        &mut self,
        file: &Path,
        line: usize,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        let body = Body::new(
            file,
            "arg".into(),
            line,
            node,
            &["name", "default", "description"],
            true,
        )?;
        let name = self.required_text(&body, "name", scope)?;
        let default = self.text(&body, "default", scope)?;
        let description = self.text(&body, "description", scope)?;
        let value = match (scope.vars.get(&name), &default) {
            (Some(given), _) => given.clone(),
            (None, Some(default)) => default.clone(),
            (None, None) => {
                return Err(LaunchError::invalid(
                    file,
                    line,
                    "arg",
                    format!("launch argument '{name}' is required (it has no default): give it as {name}:=VALUE"),
                ))
            }
        };
        scope.vars.insert(name.clone(), value.clone());
        self.declared.insert(name.clone());
        self.plan.arguments.push(DeclaredArgument {
            name,
            default,
            description,
            value,
            origin: format!("{}:{line}", file.display()),
        });
        Ok(())
    }

    fn let_(
        &mut self,
        file: &Path,
        line: usize,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        let body = Body::new(file, "let".into(), line, node, &["name", "value"], true)?;
        let name = self.required_text(&body, "name", scope)?;
        if body.get("value").is_none() {
            return Err(body.missing("value"));
        }
        let value = self.text(&body, "value", scope)?.unwrap_or_default();
        scope.vars.insert(name, value);
        Ok(())
    }

    fn include(
        &mut self,
        file: &Path,
        line: usize,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        // `include: FILE` or `include: {file: FILE, arg: [...]}`.
        let (given, file_line, arg_items): (String, usize, &[MarkedNode]) = match &node.value {
            MarkedValue::Scalar { .. } if !node.is_null() => (
                self.text_value(file, "include", node, scope)?
                    .unwrap_or_default(),
                line,
                &[],
            ),
            _ => {
                let body = Body::new(file, "include".into(), line, node, &["file", "arg"], true)?;
                let given = self.required_text(&body, "file", scope)?;
                let file_line = body.entry("file").map(|(k, _)| k.line).unwrap_or(line);
                (given, file_line, body.list("arg")?)
            }
        };
        let key = if matches!(node.value, MarkedValue::Mapping(_)) {
            "include.file"
        } else {
            "include"
        };
        if given.ends_with(".py") || given.ends_with(".xml") {
            return Err(LaunchError::invalid(
                file,
                file_line,
                key,
                format!("'{given}': only YAML launch files can be included"),
            ));
        }
        let Some(target) = resolve_relative_file(file, &given) else {
            return Err(LaunchError::invalid(
                file,
                file_line,
                key,
                format!("launch file '{given}' not found (looked next to {} and in the working directory)", file.display()),
            ));
        };
        let canonical = target.canonicalize().unwrap_or_else(|_| target.clone());
        if self.include_stack.contains(&canonical) {
            let chain: Vec<String> = self
                .include_stack
                .iter()
                .map(|p| p.display().to_string())
                .collect();
            return Err(LaunchError::invalid(
                file,
                file_line,
                key,
                format!(
                    "include cycle: {} -> {}",
                    chain.join(" -> "),
                    canonical.display()
                ),
            ));
        }
        let mut child = scope.clone();
        for (i, item) in arg_items.iter().enumerate() {
            let ctx = format!("include.arg[{i}]");
            let body = Body::new(file, ctx, item.line, item, &["name", "value"], false)?;
            let name = self.required_text(&body, "name", scope)?;
            if body.get("value").is_none() {
                return Err(body.missing("value"));
            }
            let value = self.text(&body, "value", scope)?.unwrap_or_default();
            child.vars.insert(name, value);
        }
        self.load_file(&target, &mut child)
    }

    fn group(
        &mut self,
        file: &Path,
        line: usize,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        if let MarkedValue::Sequence(children) = &node.value {
            let mut child = scope.clone();
            return self.run_actions(file, children, &mut child);
        }
        let body = Body::new(file, "group".into(), line, node, GROUP_KEYS, true)?;
        let scoped = self.bool(&body, "scoped", scope)?.unwrap_or(true);
        let forwarding = self.bool(&body, "forwarding", scope)?.unwrap_or(true);
        let push = match (
            body.get("push-ros-namespace"),
            body.get("push_ros_namespace"),
        ) {
            (Some(_), Some(_)) => {
                return Err(body.error_at(
                    "push_ros_namespace",
                    "give push-ros-namespace or push_ros_namespace, not both",
                ))
            }
            (Some(_), None) => self.text(&body, "push-ros-namespace", scope)?,
            (None, Some(_)) => self.text(&body, "push_ros_namespace", scope)?,
            (None, None) => None,
        };
        let children = body.list("children")?;
        let mut inner;
        let target: &mut Scope = if scoped {
            inner = scope.clone();
            if !forwarding {
                inner.vars.clear();
            }
            &mut inner
        } else {
            scope
        };
        if let Some(ns) = push {
            target.namespace = combine_namespace(target.namespace.as_deref(), Some(&ns));
        }
        self.run_actions(file, children, target)
    }

    fn push_namespace(
        &mut self,
        file: &Path,
        line: usize,
        action: &str,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        let ns = match &node.value {
            MarkedValue::Scalar { .. } if !node.is_null() => {
                self.text_value(file, action, node, scope)?
            }
            _ => {
                let body = Body::new(file, action.into(), line, node, &["namespace"], true)?;
                Some(self.required_text(&body, "namespace", scope)?)
            }
        };
        scope.namespace = combine_namespace(scope.namespace.as_deref(), ns.as_deref());
        Ok(())
    }

    fn node(
        &mut self,
        file: &Path,
        line: usize,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        let body = Body::new(file, "node".into(), line, node, NODE_KEYS, true)?;
        let exec = self.required_text(&body, "exec", scope)?;
        let _pkg = self.text(&body, "pkg", scope)?;
        let name = self.text(&body, "name", scope)?;
        let own_ns = self.text(&body, "namespace", scope)?;
        let mut args = self.words(&body, "args", scope)?;
        let mut extra_ros_args = self.words(&body, "ros_args", scope)?;
        // The node's DDS Security enclave (`--ros-args --enclave`): its identity and
        // permissions in the keystore of ROS_SECURITY_KEYSTORE.
        if let Some(enclave) = self.text(&body, "enclave", scope)? {
            extra_ros_args.extend(["--enclave".to_string(), enclave]);
        }

        let mut params = Vec::new();
        self.params(
            file,
            body.list("param")?,
            "",
            "node.param",
            scope,
            &mut params,
        )?;
        let mut remaps = Vec::new();
        for (i, item) in body.list("remap")?.iter().enumerate() {
            let rb = Body::new(
                file,
                format!("node.remap[{i}]"),
                item.line,
                item,
                &["from", "to"],
                false,
            )?;
            remaps.push((
                self.required_text(&rb, "from", scope)?,
                self.required_text(&rb, "to", scope)?,
            ));
        }
        let program =
            resolve_executable(&exec, &self.search).map_err(|m| body.error_at("exec", m))?;
        let namespace = combine_namespace(scope.namespace.as_deref(), own_ns.as_deref());
        args.extend(ros_args(
            name.as_deref(),
            namespace.as_deref(),
            &params,
            &remaps,
            &extra_ros_args,
        ));
        let label = name.unwrap_or_else(|| file_name_of(&exec));
        self.push_process(&body, scope, label, program, args, None)
    }

    fn executable(
        &mut self,
        file: &Path,
        line: usize,
        node: &MarkedNode,
        scope: &mut Scope,
    ) -> Result<(), LaunchError> {
        let body = Body::new(file, "executable".into(), line, node, EXECUTABLE_KEYS, true)?;
        let cmd = self.required_text(&body, "cmd", scope)?;
        let name = self.text(&body, "name", scope)?;
        let shell = self.bool(&body, "shell", scope)?.unwrap_or(false);
        let cwd = self.text(&body, "cwd", scope)?.map(PathBuf::from);
        let (program, args) = if shell {
            let extra = self.text(&body, "args", scope)?.unwrap_or_default();
            let script = if extra.is_empty() {
                cmd.clone()
            } else {
                format!("{cmd} {extra}")
            };
            (PathBuf::from("/bin/sh"), vec!["-c".to_string(), script])
        } else {
            let mut words = shell_split(&cmd).map_err(|m| body.error_at("cmd", m))?;
            if words.is_empty() {
                return Err(body.error_at("cmd", "must not be empty"));
            }
            words.extend(self.words(&body, "args", scope)?);
            let program =
                resolve_executable(&words[0], &self.search).map_err(|m| body.error_at("cmd", m))?;
            (program, words.split_off(1))
        };
        let label = name.unwrap_or_else(|| file_name_of(&program.display().to_string()));
        self.push_process(&body, scope, label, program, args, cwd)
    }

    /// Shell-split text under `key` (absent = no words).
    fn words(&self, body: &Body, key: &str, scope: &Scope) -> Result<Vec<String>, LaunchError> {
        match self.text(body, key, scope)? {
            None => Ok(Vec::new()),
            Some(text) => shell_split(&text).map_err(|m| body.error_at(key, m)),
        }
    }

    /// Adds a process with the keys common to `node` and `executable`.
    fn push_process(
        &mut self,
        body: &Body,
        scope: &Scope,
        label: String,
        program: PathBuf,
        args: Vec<String>,
        cwd: Option<PathBuf>,
    ) -> Result<(), LaunchError> {
        let respawn = self.bool(body, "respawn", scope)?.unwrap_or(false);
        let respawn_delay = self
            .seconds(body, "respawn_delay", scope)?
            .unwrap_or(Duration::ZERO);
        let respawn_max_retries = match self.text(body, "respawn_max_retries", scope)? {
            None => None,
            Some(t) => match t.trim().parse::<i64>() {
                Ok(-1) => None,
                Ok(n) if (0..=i64::from(u32::MAX)).contains(&n) => Some(n as u32),
                _ => {
                    return Err(body.error_at(
                        "respawn_max_retries",
                        format!("expected a whole number >= 0 (or -1 for no limit), found '{t}'"),
                    ))
                }
            },
        };
        let output = match self.text(body, "output", scope)?.as_deref() {
            None | Some("screen") => OutputMode::Screen,
            Some("log") => OutputMode::Log,
            Some("both") => OutputMode::Both,
            Some(other) => {
                return Err(body.error_at(
                    "output",
                    format!("expected screen, log or both, found '{other}'"),
                ))
            }
        };
        let mut env = Vec::new();
        for (i, item) in body.list("env")?.iter().enumerate() {
            let eb = Body::new(
                body.file,
                format!("{}.env[{i}]", body.context),
                item.line,
                item,
                &["name", "value"],
                false,
            )?;
            let name = self.required_text(&eb, "name", scope)?;
            let value = self.text(&eb, "value", scope)?.unwrap_or_default();
            env.push((name, value));
        }
        self.plan.processes.push(ProcessSpec {
            label,
            program,
            args,
            env,
            cwd,
            respawn,
            respawn_delay,
            respawn_max_retries,
            output,
            origin: format!("{}:{}", body.file.display(), body.line),
        });
        Ok(())
    }

    /// `param` items, in order, into `out`; nested `param` lists get `prefix` + `name.`.
    fn params(
        &self,
        file: &Path,
        items: &[MarkedNode],
        prefix: &str,
        context: &str,
        scope: &Scope,
        out: &mut Vec<ParamArg>,
    ) -> Result<(), LaunchError> {
        for (i, item) in items.iter().enumerate() {
            let ctx = format!("{context}[{i}]");
            let body = Body::new(
                file,
                ctx.clone(),
                item.line,
                item,
                &["name", "value", "from", "param"],
                false,
            )?;
            if body.get("from").is_some() {
                if let Some(other) = ["name", "value", "param"]
                    .into_iter()
                    .find(|k| body.get(k).is_some())
                {
                    return Err(body.error_at(
                        other,
                        "a parameter item has either 'from' (a parameters file) or 'name'",
                    ));
                }
                let given = self.required_text(&body, "from", scope)?;
                let path = resolve_relative_file(file, &given).ok_or_else(|| {
                    body.error_at("from", format!("parameters file '{given}' not found"))
                })?;
                out.push(ParamArg::File(path));
                continue;
            }
            let name = self.required_text(&body, "name", scope)?;
            match (body.get("value"), body.get("param")) {
                (Some(_), Some(_)) => {
                    return Err(body.error_at(
                        "param",
                        "a parameter has either 'value' or nested 'param', not both",
                    ))
                }
                (Some(value), None) => {
                    let rendered =
                        self.render_param(file, &body.key_path("value"), value, scope, false)?;
                    out.push(ParamArg::Value {
                        name: format!("{prefix}{name}"),
                        value: rendered,
                    });
                }
                (None, Some(_)) => {
                    let nested = body.list("param")?;
                    self.params(
                        file,
                        nested,
                        &format!("{prefix}{name}."),
                        &format!("{ctx}.param"),
                        scope,
                        out,
                    )?;
                }
                (None, None) => return Err(body.missing("value")),
            }
        }
        Ok(())
    }

    /// A parameter value as YAML text for `-p name:=VALUE` (see the module docs of
    /// `command_line`): plain scalars and substituted text as written (the node reads them as
    /// YAML, as ROS 2 launch does), literal quoted strings re-quoted only when a YAML reader
    /// would otherwise take them for something else (`'0042'` stays a string), collections in
    /// flow syntax.
    fn render_param(
        &self,
        file: &Path,
        key: &str,
        node: &MarkedNode,
        scope: &Scope,
        in_flow: bool,
    ) -> Result<String, LaunchError> {
        match &node.value {
            MarkedValue::Scalar { text, plain } => {
                let s = self.subst(file, node.line, key, text, scope)?;
                // ROS types a substituted value by reading it as YAML even when it was quoted
                // (`value: "$(var rate)"` gives an int), so only literal quoted text stays a string.
                let typed_by_content = *plain || text.contains("$(");
                if typed_by_content {
                    if s.is_empty() && !in_flow {
                        return Err(LaunchError::invalid(
                            file,
                            node.line,
                            key,
                            "empty value (write '' for an empty string)",
                        ));
                    }
                    Ok(if s.is_empty() { "null".into() } else { s })
                } else {
                    let flow_special = in_flow && s.contains([',', '[', ']', '{', '}', ':', '#']);
                    Ok(if yaml_string_needs_quotes(&s) || flow_special {
                        yaml_single_quote(&s)
                    } else {
                        s
                    })
                }
            }
            MarkedValue::Sequence(items) => {
                let parts: Result<Vec<String>, LaunchError> = items
                    .iter()
                    .map(|item| self.render_param(file, key, item, scope, true))
                    .collect();
                Ok(format!("[{}]", parts?.join(", ")))
            }
            MarkedValue::Mapping(entries) => {
                let mut parts = Vec::new();
                for (k, v) in entries {
                    let k = self.render_param(file, key, k, scope, true)?;
                    let v = self.render_param(file, key, v, scope, true)?;
                    parts.push(format!("{k}: {v}"));
                }
                Ok(format!("{{{}}}", parts.join(", ")))
            }
        }
    }

    /// `$(find-pkg-share PKG)`. `metrocell` and `metrocell_msgs` are this repository: the
    /// directory holding `launch-configs/` (see [`LaunchOptions::share_dir`]). Other packages are
    /// looked for as `share/PKG` under each `AMENT_PREFIX_PATH` entry, as ROS 2 installs them.
    fn find_pkg_share(&self, current_file: &Path, pkg: &str) -> Result<PathBuf, String> {
        if pkg == "metrocell" || pkg == "metrocell_msgs" {
            if let Some(dir) = &self.options.share_dir {
                return Ok(dir.clone());
            }
            if let Some(dir) = self
                .options
                .env_var("METROCELL_SHARE")
                .filter(|d| !d.is_empty())
            {
                return Ok(PathBuf::from(dir));
            }
            let start = current_file
                .canonicalize()
                .unwrap_or_else(|_| current_file.to_path_buf());
            return start
                .ancestors()
                .skip(1)
                .find(|dir| dir.join("launch-configs").is_dir())
                .map(Path::to_path_buf)
                .ok_or_else(|| {
                    format!(
                        "package '{pkg}': no directory holding launch-configs/ above {} (set METROCELL_SHARE)",
                        current_file.display()
                    )
                });
        }
        let prefixes = self
            .options
            .env_var("AMENT_PREFIX_PATH")
            .unwrap_or_default();
        std::env::split_paths(&prefixes)
            .map(|prefix| prefix.join("share").join(pkg))
            .find(|dir| dir.is_dir())
            .ok_or_else(|| {
                format!(
                    "package '{pkg}' not found (not metrocell, and not under AMENT_PREFIX_PATH)"
                )
            })
    }
}

/// `given` as is when absolute, else next to `including_file`, else relative to the working
/// directory; `None` when no such file exists.
fn resolve_relative_file(including_file: &Path, given: &str) -> Option<PathBuf> {
    let given_path = Path::new(given);
    if given_path.is_absolute() {
        return given_path.is_file().then(|| given_path.to_path_buf());
    }
    let beside = including_file
        .parent()
        .unwrap_or(Path::new("."))
        .join(given_path);
    if beside.is_file() {
        return Some(beside);
    }
    given_path.is_file().then(|| given_path.to_path_buf())
}

fn file_name_of(exec: &str) -> String {
    Path::new(exec)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| exec.to_string())
}

/// Second and later processes with an already used label get `-2`, `-3`, ...
fn make_labels_unique(processes: &mut [ProcessSpec]) {
    let mut seen: HashMap<String, usize> = HashMap::new();
    for p in processes.iter_mut() {
        let count = seen.entry(p.label.clone()).or_insert(0);
        *count += 1;
        if *count > 1 {
            p.label = format!("{}-{}", p.label, count);
        }
    }
}
