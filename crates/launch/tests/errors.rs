//! Every kind of mistake in a launch file is reported with the file, the 1-based line and the key.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use metrocell_launch::{load_launch_plan, parse_launch_arguments, LaunchError, LaunchOptions};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A fresh directory with an executable `tool` in it (the search path of every case).
fn workdir() -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir = std::env::temp_dir().join(format!("metrocell-launch-err-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let tool = dir.join("tool");
    std::fs::write(&tool, "#!/bin/sh\n").unwrap();
    std::fs::set_permissions(&tool, std::fs::Permissions::from_mode(0o755)).unwrap();
    dir
}

fn options(dir: &Path) -> LaunchOptions {
    LaunchOptions {
        executable_search_path: Some(vec![dir.to_path_buf()]),
        environment: Some(Default::default()),
        ..LaunchOptions::default()
    }
}

/// Writes `text` as `name` in a fresh dir, loads it, returns the error message and the file path.
fn error_of(name: &str, text: &str, args: &[&str]) -> (String, PathBuf) {
    let dir = workdir();
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    let args = parse_launch_arguments(args).unwrap();
    let err = load_launch_plan(&file, &args, &options(&dir)).expect_err("loading should fail");
    eprintln!("{err}");
    std::fs::remove_dir_all(&dir).unwrap();
    (err.to_string(), file)
}

fn assert_starts(message: &str, prefix: &str) {
    assert!(
        message.starts_with(prefix),
        "message:  {message}\nexpected: {prefix}..."
    );
}

#[test]
fn unknown_key_names_file_line_key_and_the_allowed_keys() {
    let text = "launch:\n  - node:\n      pkg: metrocell\n      exec: tool\n      pkgg: oops\n";
    let (msg, file) = error_of("x.yaml", text, &[]);
    assert_eq!(
        msg,
        format!(
            "{}:5: node: unknown key 'pkgg' (expected one of pkg, exec, name, namespace, param, remap, args, \
             ros_args, enclave, respawn, respawn_delay, respawn_max_retries, output, env, if, unless)",
            file.display()
        )
    );
}

#[test]
fn yaml_syntax_error_has_line_and_column() {
    let text = "launch:\n  - node:\n      exec: tool\n      name: [unclosed\n  - arg: {name: a}\n";
    let (msg, file) = error_of("syntax.yaml", text, &[]);
    assert_starts(&msg, &format!("{}:5:", file.display()));
    assert!(msg.contains("YAML syntax error"), "{msg}");
}

#[test]
fn tab_indentation_is_a_syntax_error() {
    let (msg, file) = error_of("tabs.yaml", "launch:\n  - node:\n\texec: tool\n", &[]);
    assert_starts(&msg, &format!("{}:3:", file.display()));
}

#[test]
fn wrong_value_types_name_the_key() {
    let cases: &[(&str, &str)] = &[
        ("launch:\n  - node:\n      exec: tool\n      respawn_delay: soon\n", "4: node.respawn_delay: expected a non-negative number of seconds, found 'soon'"),
        ("launch:\n  - node:\n      exec: tool\n      respawn: maybe\n", "4: node.respawn: expected true or false, found 'maybe'"),
        ("launch:\n  - node:\n      exec: tool\n      param: {name: a, value: 1}\n", "4: node.param: expected a list, found a mapping"),
        ("launch:\n  - node:\n      exec: tool\n      name: [a, b]\n", "4: node.name: expected a text value, found a list"),
        ("launch:\n  - node:\n      exec: tool\n      output: loud\n", "4: node.output: expected screen, log or both, found 'loud'"),
        ("launch:\n  - node:\n      exec: tool\n      remap:\n        - from: a\n", "5: node.remap[0]: missing required key 'to'"),
        ("launch:\n  - node:\n      exec: tool\n      param:\n        - name: a\n          valu: 1\n", "6: node.param[0]: unknown key 'valu' (expected one of name, value, from, param)"),
        ("launch:\n  - node:\n      exec: tool\n      param:\n        - name: a\n", "5: node.param[0]: missing required key 'value'"),
        ("launch:\n  - node:\n      exec: tool\n      respawn_max_retries: lots\n", "4: node.respawn_max_retries: expected a whole number"),
        ("launch:\n  - node: just-a-string\n", "2: node: expected a mapping of keys, found a scalar"),
        ("launch:\n  - group:\n      scoped: perhaps\n", "3: group.scoped: expected true or false, found 'perhaps'"),
        ("launch: {node: {exec: tool}}\n", "1: launch: expected a list of actions, found a mapping"),
        ("lunch: []\n", "1: (top level): unknown key 'lunch' (expected one of launch)"),
    ];
    for (text, expected) in cases {
        let (msg, file) = error_of("types.yaml", text, &[]);
        assert_starts(&msg, &format!("{}:{expected}", file.display()));
    }
}

#[test]
fn missing_exec_names_the_node_line() {
    let text =
        "launch:\n  - arg: {name: a, default: x}\n  - node:\n      pkg: metrocell\n      name: n\n";
    let (msg, file) = error_of("noexec.yaml", text, &[]);
    assert_eq!(
        msg,
        format!("{}:3: node: missing required key 'exec'", file.display())
    );
}

#[test]
fn unknown_action_and_two_key_action() {
    let (msg, file) = error_of("act.yaml", "launch:\n  - nod:\n      exec: tool\n", &[]);
    assert_starts(
        &msg,
        &format!(
            "{}:2: launch: unknown action 'nod' (expected one of arg, let, include",
            file.display()
        ),
    );
    let (msg, file) = error_of("act2.yaml", "launch:\n  - node:\n    exec: tool\n", &[]);
    assert_starts(
        &msg,
        &format!(
            "{}:2: launch: an action is a mapping with exactly one key",
            file.display()
        ),
    );
}

#[test]
fn unknown_substitution_names_it() {
    let text = "launch:\n  - node:\n      exec: tool\n      name: $(eval 1 + 1)\n";
    let (msg, file) = error_of("subst.yaml", text, &[]);
    assert_eq!(
        msg,
        format!(
            "{}:4: node.name: unknown substitution '$(eval)' (known: var, env, optenv, find-pkg-share, dirname, filename)",
            file.display()
        )
    );
    let (msg, file) = error_of(
        "var.yaml",
        "launch:\n  - node:\n      exec: tool\n      args: $(var nope)\n",
        &[],
    );
    assert_starts(
        &msg,
        &format!(
            "{}:4: node.args: launch configuration 'nope' is not defined",
            file.display()
        ),
    );
    let (msg, file) = error_of(
        "env.yaml",
        "launch:\n  - let: {name: a, value: $(env NOT_SET_X)}\n",
        &[],
    );
    assert_starts(
        &msg,
        &format!(
            "{}:2: let.value: environment variable 'NOT_SET_X' is not set",
            file.display()
        ),
    );
}

#[test]
fn include_not_found_names_including_file_and_line() {
    let text =
        "launch:\n  - arg: {name: a, default: x}\n  - include:\n      file: missing.launch.yaml\n";
    let (msg, file) = error_of("inc.yaml", text, &[]);
    assert_starts(
        &msg,
        &format!(
            "{}:4: include.file: launch file 'missing.launch.yaml' not found",
            file.display()
        ),
    );
    let (msg, file) = error_of("inc2.yaml", "launch:\n  - include: other.launch.py\n", &[]);
    assert_starts(
        &msg,
        &format!(
            "{}:2: include: 'other.launch.py': only YAML launch files can be included",
            file.display()
        ),
    );
}

#[test]
fn errors_inside_an_included_file_name_that_file() {
    let dir = workdir();
    std::fs::write(
        dir.join("inner.yaml"),
        "launch:\n  - arg:\n      name: needed\n",
    )
    .unwrap();
    let outer = dir.join("outer.yaml");
    std::fs::write(&outer, "launch:\n  - include:\n      file: inner.yaml\n").unwrap();
    let msg = load_launch_plan(&outer, &[], &options(&dir))
        .unwrap_err()
        .to_string();
    assert_eq!(
        msg,
        format!(
            "{}:2: arg: launch argument 'needed' is required (it has no default): give it as needed:=VALUE",
            dir.join("inner.yaml").display()
        )
    );
    // Giving it on the command line or through the include's `arg` list fixes it.
    let args = parse_launch_arguments(&["needed:=1"]).unwrap();
    assert!(load_launch_plan(&outer, &args, &options(&dir)).is_ok());
}

#[test]
fn include_cycle_is_reported() {
    let dir = workdir();
    std::fs::write(dir.join("a.yaml"), "launch:\n  - include: b.yaml\n").unwrap();
    std::fs::write(dir.join("b.yaml"), "launch:\n  - include: a.yaml\n").unwrap();
    let msg = load_launch_plan(&dir.join("a.yaml"), &[], &options(&dir))
        .unwrap_err()
        .to_string();
    assert_starts(
        &msg,
        &format!(
            "{}:2: include: include cycle:",
            dir.join("b.yaml").display()
        ),
    );
}

#[test]
fn executable_not_found_names_exec_key() {
    let (msg, file) = error_of(
        "exe.yaml",
        "launch:\n  - node:\n      pkg: p\n      exec: no_such_node\n",
        &[],
    );
    assert_starts(
        &msg,
        &format!(
            "{}:4: node.exec: executable 'no_such_node' not found (searched:",
            file.display()
        ),
    );
    let (msg, file) = error_of(
        "pf.yaml",
        "launch:\n  - node:\n      exec: tool\n      param:\n        - from: nope.yaml\n",
        &[],
    );
    assert_starts(
        &msg,
        &format!(
            "{}:5: node.param[0].from: parameters file 'nope.yaml' not found",
            file.display()
        ),
    );
}

#[test]
fn command_line_argument_problems() {
    let (msg, _) = error_of(
        "cli.yaml",
        "launch:\n  - arg: {name: rate, default: '1'}\n",
        &["rat:=2"],
    );
    assert_eq!(
        msg,
        "launch argument 'rat' is not declared by the launch file (declared: rate)"
    );
    let err = parse_launch_arguments(&["rate=2"]).unwrap_err();
    assert!(matches!(err, LaunchError::BadArgumentSyntax { .. }));
    assert_eq!(
        err.to_string(),
        "launch argument 'rate=2' is not of the form name:=value"
    );
}

#[test]
fn unreadable_file() {
    let err = load_launch_plan(
        Path::new("/nonexistent/x.yaml"),
        &[],
        &LaunchOptions::default(),
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("cannot read launch file /nonexistent/x.yaml:"),
        "{err}"
    );
}
