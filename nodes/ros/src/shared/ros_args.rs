//! The `--ros-args` part of a ROS 2 node's command line, as rcl reads it:
//!
//! ```text
//! sim_node [own args] --ros-args -r __ns:=/env_00 -r __node:=sim -r joint_states:=js \
//!          -p mode:=lockstep --params-file params/sim.yaml --log-level debug [--] [own args]
//! ```
//!
//! Several `--ros-args` sections may appear; `--` (or the end) closes one. Arguments outside the
//! sections are the program's own and are returned untouched.

use std::fmt;
use std::path::PathBuf;

/// A parameter value given with `-p name:=value` (YAML scalars and flow sequences, as rcl).
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// `true` / `false`.
    Bool(bool),
    /// An integer.
    Integer(i64),
    /// A floating-point number.
    Double(f64),
    /// Anything else (quotes removed).
    String(String),
    /// `[a, b, ...]`.
    Array(Vec<ParamValue>),
}

impl ParamValue {
    /// Parse a value the way the ROS 2 command line does (YAML rules for scalars).
    pub fn parse(text: &str) -> ParamValue {
        let t = text.trim();
        if let Some(inner) = t.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            if inner.trim().is_empty() {
                return ParamValue::Array(Vec::new());
            }
            return ParamValue::Array(inner.split(',').map(ParamValue::parse).collect());
        }
        match t {
            "true" | "True" | "TRUE" => return ParamValue::Bool(true),
            "false" | "False" | "FALSE" => return ParamValue::Bool(false),
            _ => {}
        }
        if let Ok(i) = t.parse::<i64>() {
            return ParamValue::Integer(i);
        }
        if let Ok(f) = t.parse::<f64>()
            && t.chars().any(|c| c.is_ascii_digit())
        {
            return ParamValue::Double(f);
        }
        let unquoted = match t.chars().next() {
            Some(q @ ('"' | '\'')) if t.len() >= 2 && t.ends_with(q) => &t[1..t.len() - 1],
            _ => t,
        };
        ParamValue::String(unquoted.to_string())
    }
}

/// What the `--ros-args` sections asked for.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RosArgs {
    /// `-r __ns:=/ns`: the node's namespace.
    pub namespace: Option<String>,
    /// `-r __node:=name` (or `__name`): the node's name.
    pub node_name: Option<String>,
    /// Other remaps, `from:=to`, in order.
    pub remaps: Vec<(String, String)>,
    /// `-p name:=value`, in order (later ones win).
    pub params: Vec<(String, ParamValue)>,
    /// `--params-file FILE`, in order.
    pub params_files: Vec<PathBuf>,
    /// `--log-level LEVEL`.
    pub log_level: Option<String>,
    /// `-e/--enclave NAME`: the security enclave (default `/`).
    pub enclave: Option<String>,
    /// The program's own arguments (outside the sections).
    pub other: Vec<String>,
}

/// A malformed `--ros-args` section.
#[derive(Debug, Clone, PartialEq)]
pub struct RosArgsError(pub String);

impl fmt::Display for RosArgsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl std::error::Error for RosArgsError {}

const LOG_LEVELS: [&str; 5] = ["debug", "info", "warn", "error", "fatal"];

/// Whether `name` is a valid ROS name token sequence (letters, digits, `_`, separated by `/`,
/// no token starting with a digit, no `//`), optionally absolute.
pub fn is_valid_name(name: &str, allow_absolute: bool) -> bool {
    let body = match name.strip_prefix('/') {
        Some(rest) if allow_absolute => rest,
        Some(_) => return false,
        None => name,
    };
    if body.is_empty() {
        return name == "/" && allow_absolute;
    }
    body.split('/').all(|token| {
        !token.is_empty()
            && !token.starts_with(|c: char| c.is_ascii_digit())
            && token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    })
}

/// Whether `name` is a fully qualified ROS name (a namespace or an enclave): `/`, or
/// `/`-separated tokens as [`is_valid_name`] takes them, starting with `/`.
pub fn is_fully_qualified_name(name: &str) -> bool {
    name.starts_with('/') && is_valid_name(name, true)
}

fn split_assignment<'a>(flag: &str, text: &'a str) -> Result<(&'a str, &'a str), RosArgsError> {
    text.split_once(":=")
        .ok_or_else(|| RosArgsError(format!("`{flag} {text}` needs the form name:=value")))
}

/// Parse a full argument list (without the program name).
pub fn parse(args: &[String]) -> Result<RosArgs, RosArgsError> {
    let mut out = RosArgs::default();
    let mut in_section = false;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        if arg == "--ros-args" {
            in_section = true;
            continue;
        }
        if !in_section {
            out.other.push(arg.clone());
            continue;
        }
        let mut value = |flag: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| RosArgsError(format!("`{flag}` needs a value after it")))
        };
        match arg.as_str() {
            "--" => in_section = false,
            "-r" | "--remap" => {
                let text = value(arg)?;
                let (from, to) = split_assignment(arg, &text)?;
                match from {
                    "__ns" => {
                        if !is_fully_qualified_name(to) {
                            return Err(RosArgsError(format!(
                                "namespace `{to}` is invalid; it must be absolute, e.g. /env_00"
                            )));
                        }
                        out.namespace = Some(to.trim_end_matches('/').to_string())
                            .filter(|n| !n.is_empty())
                            .or(Some("/".into()));
                    }
                    "__node" | "__name" => {
                        if !is_valid_name(to, false) || to.contains('/') {
                            return Err(RosArgsError(format!(
                                "node name `{to}` is invalid; use letters, digits and _ (not starting with a digit)"
                            )));
                        }
                        out.node_name = Some(to.to_string());
                    }
                    _ => {
                        for name in [from, to] {
                            if !is_valid_name(
                                name.trim_start_matches('~').trim_start_matches('/'),
                                false,
                            ) {
                                return Err(RosArgsError(format!(
                                    "remap `{from}:={to}`: `{name}` is not a valid ROS name"
                                )));
                            }
                        }
                        out.remaps.push((from.to_string(), to.to_string()));
                    }
                }
            }
            "-p" | "--param" => {
                let text = value(arg)?;
                let (name, v) = split_assignment(arg, &text)?;
                if name.is_empty() {
                    return Err(RosArgsError(format!(
                        "`{arg} {text}` has an empty parameter name"
                    )));
                }
                out.params.push((name.to_string(), ParamValue::parse(v)));
            }
            "--params-file" => out.params_files.push(PathBuf::from(value(arg)?)),
            "--log-level" => {
                let level = value(arg)?;
                // `--log-level name:=level` targets one logger; we have one logger per node.
                let level = level
                    .split_once(":=")
                    .map_or(level.as_str(), |(_, l)| l)
                    .to_ascii_lowercase();
                if !LOG_LEVELS.contains(&level.as_str()) {
                    return Err(RosArgsError(format!(
                        "log level `{level}` is invalid; valid: {}",
                        LOG_LEVELS.join(", ")
                    )));
                }
                out.log_level = Some(level);
            }
            "-e" | "--enclave" => {
                let enclave = value(arg)?;
                if !is_fully_qualified_name(&enclave) {
                    return Err(RosArgsError(format!(
                        "enclave `{enclave}` is not a fully qualified name such as /composuite/sim"
                    )));
                }
                out.enclave = Some(enclave);
            }
            other => {
                return Err(RosArgsError(format!(
                    "unknown --ros-args option `{other}`; valid: -r/--remap from:=to, -p/--param name:=value, \
                     --params-file FILE, --log-level LEVEL, -e/--enclave NAME, --"
                )));
            }
        }
    }
    Ok(out)
}

impl RosArgs {
    /// The name a relative topic `name` has after the remaps (exact-match rules, as rcl).
    pub fn remapped<'a>(&'a self, name: &'a str) -> &'a str {
        self.remaps
            .iter()
            .rev()
            .find(|(from, _)| from == name)
            .map_or(name, |(_, to)| to.as_str())
    }

    /// The last value given for a parameter on the command line.
    pub fn param(&self, name: &str) -> Option<&ParamValue> {
        self.params
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }
}
