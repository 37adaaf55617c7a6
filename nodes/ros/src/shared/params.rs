//! Node parameters: what each node declares, and where values come from — the defaults, then
//! `--params-file` files (`/**: ros__parameters:` form, as rcl reads them), then `-p name:=value`
//! (later wins). Values are checked against the declaration before the node starts, and again
//! when set through the parameter services.

use std::path::Path;

use ros2_client::ParameterValue;
use yaml_rust2::{Yaml, YamlLoader};

use crate::shared::ros_args::{ParamValue, RosArgs};

/// One declared parameter.
#[derive(Debug, Clone)]
pub struct ParamSpec {
    /// Name (`mode`, `rate_hz`, ...).
    pub name: &'static str,
    /// Value when nothing sets it; also fixes the parameter's type.
    pub default: fn() -> ParameterValue,
    /// One line for `--help` and the describe service.
    pub description: &'static str,
    /// Extra check beyond the type; `Err` says what is valid.
    pub check: fn(&ParameterValue) -> Result<(), String>,
}

/// Accept any value of the declared type.
pub fn any_value(_: &ParameterValue) -> Result<(), String> {
    Ok(())
}

/// Accept a finite double > 0 (periods, factors, timeouts).
pub fn positive_number(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::Double(d) if d.is_finite() && *d > 0.0 => Ok(()),
        _ => Err("must be a finite number > 0".into()),
    }
}

/// The ROS type name of a value, for messages.
pub fn type_name(v: &ParameterValue) -> &'static str {
    match v {
        ParameterValue::NotSet => "not set",
        ParameterValue::Boolean(_) => "bool",
        ParameterValue::Integer(_) => "integer",
        ParameterValue::Double(_) => "double",
        ParameterValue::String(_) => "string",
        ParameterValue::ByteArray(_) => "byte array",
        ParameterValue::BooleanArray(_) => "bool array",
        ParameterValue::IntegerArray(_) => "integer array",
        ParameterValue::DoubleArray(_) => "double array",
        ParameterValue::StringArray(_) => "string array",
    }
}

impl ParamSpec {
    /// Check `value` for this parameter: its type (an integer is accepted for a double, as rcl
    /// does for YAML), then the parameter's own rule. Returns the value in the declared type.
    pub fn accept(&self, value: ParameterValue) -> Result<ParameterValue, String> {
        let default = (self.default)();
        let value = match (&default, value) {
            (ParameterValue::Double(_), ParameterValue::Integer(i)) => {
                ParameterValue::Double(i as f64)
            }
            (_, v) => v,
        };
        if std::mem::discriminant(&default) != std::mem::discriminant(&value) {
            return Err(format!(
                "parameter `{}` is a {}, not a {} ({:?})",
                self.name,
                type_name(&default),
                type_name(&value),
                value
            ));
        }
        (self.check)(&value).map_err(|e| format!("parameter `{}`: {e}", self.name))?;
        Ok(value)
    }
}

/// Convert a command-line / YAML value to a ROS parameter value.
pub fn from_arg(value: &ParamValue) -> Result<ParameterValue, String> {
    Ok(match value {
        ParamValue::Bool(b) => ParameterValue::Boolean(*b),
        ParamValue::Integer(i) => ParameterValue::Integer(*i),
        ParamValue::Double(d) => ParameterValue::Double(*d),
        ParamValue::String(s) => ParameterValue::String(s.clone()),
        ParamValue::Array(items) => {
            if items.iter().all(|i| matches!(i, ParamValue::Bool(_))) {
                ParameterValue::BooleanArray(
                    items
                        .iter()
                        .map(|i| matches!(i, ParamValue::Bool(true)))
                        .collect(),
                )
            } else if items.iter().all(|i| matches!(i, ParamValue::Integer(_))) {
                ParameterValue::IntegerArray(
                    items
                        .iter()
                        .filter_map(|i| match i {
                            ParamValue::Integer(v) => Some(*v),
                            _ => None,
                        })
                        .collect(),
                )
            } else if items
                .iter()
                .all(|i| matches!(i, ParamValue::Integer(_) | ParamValue::Double(_)))
            {
                ParameterValue::DoubleArray(
                    items
                        .iter()
                        .filter_map(|i| match i {
                            ParamValue::Integer(v) => Some(*v as f64),
                            ParamValue::Double(v) => Some(*v),
                            _ => None,
                        })
                        .collect(),
                )
            } else if items.iter().all(|i| matches!(i, ParamValue::String(_))) {
                ParameterValue::StringArray(
                    items
                        .iter()
                        .filter_map(|i| match i {
                            ParamValue::String(v) => Some(v.clone()),
                            _ => None,
                        })
                        .collect(),
                )
            } else {
                return Err(format!("array {value:?} mixes element types"));
            }
        }
    })
}

fn from_yaml(y: &Yaml) -> Result<ParamValue, String> {
    Ok(match y {
        Yaml::Boolean(b) => ParamValue::Bool(*b),
        Yaml::Integer(i) => ParamValue::Integer(*i),
        Yaml::Real(r) => ParamValue::Double(
            r.parse::<f64>()
                .map_err(|_| format!("`{r}` is not a number"))?,
        ),
        Yaml::String(s) => ParamValue::String(s.clone()),
        Yaml::Array(items) => {
            ParamValue::Array(items.iter().map(from_yaml).collect::<Result<_, _>>()?)
        }
        other => return Err(format!("unsupported parameter value {other:?}")),
    })
}

/// Whether a params-file key addresses the node `fully_qualified` (`/ns/name`): `/**`,
/// `/**/name`, the full name, or the bare name, as rcl matches them.
fn key_matches(key: &str, fully_qualified: &str) -> bool {
    let base = fully_qualified
        .rsplit('/')
        .next()
        .unwrap_or(fully_qualified);
    let key = key.trim();
    key == "/**"
        || key == "**"
        || key == fully_qualified
        || key == base
        || key.strip_prefix("/**/") == Some(base)
        || key
            .strip_suffix("/**")
            .is_some_and(|ns| fully_qualified.starts_with(&format!("{ns}/")) || ns.is_empty())
}

/// Flatten nested maps under `ros__parameters` into dotted names (`a: {b: 1}` → `a.b`).
fn flatten(prefix: &str, y: &Yaml, out: &mut Vec<(String, ParamValue)>) -> Result<(), String> {
    if let Yaml::Hash(map) = y {
        for (k, v) in map {
            let key = k
                .as_str()
                .map(str::to_string)
                .or_else(|| k.as_i64().map(|i| i.to_string()))
                .ok_or_else(|| format!("parameter name {k:?} is not a string"))?;
            let name = if prefix.is_empty() {
                key
            } else {
                format!("{prefix}.{key}")
            };
            flatten(&name, v, out)?;
        }
        Ok(())
    } else {
        out.push((prefix.to_string(), from_yaml(y)?));
        Ok(())
    }
}

/// The parameters a params file sets for node `fully_qualified`, in file order.
pub fn read_params_file(
    path: &Path,
    fully_qualified: &str,
) -> Result<Vec<(String, ParamValue)>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read params file {}: {e}", path.display()))?;
    parse_params_yaml(&text, fully_qualified)
        .map_err(|e| format!("params file {}: {e}", path.display()))
}

/// [`read_params_file`] on text.
pub fn parse_params_yaml(
    text: &str,
    fully_qualified: &str,
) -> Result<Vec<(String, ParamValue)>, String> {
    let docs = YamlLoader::load_from_str(text).map_err(|e| format!("not YAML: {e}"))?;
    let mut out = Vec::new();
    for doc in &docs {
        let Yaml::Hash(nodes) = doc else {
            return Err("expected `<node name>: ros__parameters: {...}` at the top".into());
        };
        for (key, body) in nodes {
            let key = key.as_str().ok_or("node keys must be strings")?;
            if !key_matches(key, fully_qualified) {
                continue;
            }
            match body["ros__parameters"] {
                Yaml::BadValue => {
                    return Err(format!("`{key}:` has no `ros__parameters:` map under it"));
                }
                ref params => flatten("", params, &mut out)?,
            }
        }
    }
    Ok(out)
}

/// Every declared parameter's starting value, and the names given that no parameter has.
pub type Resolved = (Vec<(String, ParameterValue)>, Vec<String>);

/// The starting value of every declared parameter: defaults, then params files, then `-p`.
/// Unknown names are reported back (rcl ignores them; a node should say so).
pub fn resolve(
    specs: &[ParamSpec],
    args: &RosArgs,
    fully_qualified: &str,
) -> Result<Resolved, String> {
    let mut values: Vec<(String, ParameterValue)> = specs
        .iter()
        .map(|s| (s.name.to_string(), (s.default)()))
        .collect();
    let mut unknown = Vec::new();
    let mut given: Vec<(String, ParamValue)> = Vec::new();
    for file in &args.params_files {
        given.extend(read_params_file(file, fully_qualified)?);
    }
    given.extend(args.params.iter().cloned());
    for (name, value) in given {
        if name == "use_sim_time" {
            continue; // every node has it; ours never follow an external clock
        }
        let Some(spec) = specs.iter().find(|s| s.name == name) else {
            unknown.push(name);
            continue;
        };
        let value = spec.accept(from_arg(&value)?)?;
        let slot = values
            .iter_mut()
            .find(|(n, _)| *n == name)
            .expect("every spec has a slot");
        slot.1 = value;
    }
    Ok((values, unknown))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode_check(v: &ParameterValue) -> Result<(), String> {
        match v {
            ParameterValue::String(s) if s == "lockstep" || s == "realtime" => Ok(()),
            _ => Err("valid: lockstep, realtime".into()),
        }
    }

    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec {
                name: "mode",
                default: || ParameterValue::String("lockstep".into()),
                description: "stepping mode",
                check: mode_check,
            },
            ParamSpec {
                name: "rate",
                default: || ParameterValue::Double(20.0),
                description: "rate",
                check: any_value,
            },
        ]
    }

    #[test]
    fn files_then_command_line_override_defaults() {
        let dir = std::env::temp_dir().join(format!("params-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("p.yaml");
        std::fs::write(
            &file,
            "/**:\n  ros__parameters:\n    mode: realtime\n    rate: 50\n/other:\n  ros__parameters:\n    rate: 1.0\n",
        )
        .unwrap();
        let args = RosArgs {
            params_files: vec![file],
            params: vec![("rate".into(), ParamValue::Double(10.5))],
            ..Default::default()
        };
        let (values, unknown) = resolve(&specs(), &args, "/env_00/sim").unwrap();
        assert_eq!(values[0].1, ParameterValue::String("realtime".into()));
        assert_eq!(values[1].1, ParameterValue::Double(10.5));
        assert!(unknown.is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_values_are_refused_with_what_is_valid() {
        let args = RosArgs {
            params: vec![("mode".into(), ParamValue::String("fast".into()))],
            ..Default::default()
        };
        let err = resolve(&specs(), &args, "/sim").unwrap_err();
        assert!(err.contains("lockstep, realtime"), "{err}");
        let args = RosArgs {
            params: vec![("rate".into(), ParamValue::String("x".into()))],
            ..Default::default()
        };
        let err = resolve(&specs(), &args, "/sim").unwrap_err();
        assert!(err.contains("is a double, not a string"), "{err}");
    }

    #[test]
    fn node_keys_match_like_rcl() {
        assert!(key_matches("/**", "/env_00/sim"));
        assert!(key_matches("/**/sim", "/env_00/sim"));
        assert!(key_matches("/env_00/sim", "/env_00/sim"));
        assert!(key_matches("sim", "/sim"));
        assert!(key_matches("/env_00/**", "/env_00/sim"));
        assert!(!key_matches("/env_01/sim", "/env_00/sim"));
        assert!(!key_matches("/**/reward", "/env_00/sim"));
    }

    #[test]
    fn unknown_names_are_reported() {
        let text = "/**:\n  ros__parameters:\n    nested:\n      a: [1, 2]\n";
        let got = parse_params_yaml(text, "/sim").unwrap();
        assert_eq!(
            got,
            vec![(
                "nested.a".to_string(),
                ParamValue::Array(vec![ParamValue::Integer(1), ParamValue::Integer(2)])
            )]
        );
        let args = RosArgs {
            params: vec![("bogus".into(), ParamValue::Integer(1))],
            ..Default::default()
        };
        let (_, unknown) = resolve(&specs(), &args, "/sim").unwrap();
        assert_eq!(unknown, vec!["bogus".to_string()]);
    }
}
