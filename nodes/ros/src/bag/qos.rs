//! The QoS profiles a bag stores per topic: what the publishers offered, in rosbag2's
//! metadata version 9 form (policy names as strings, durations as `{sec, nsec}`), used both in
//! `metadata.yaml` and in each MCAP channel's `offered_qos_profiles`
//! (docs/src/rosbag2-format.md §1.3).

use std::fmt::Write;

use yaml_rust2::Yaml;

/// A duration as rosbag2 writes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QosDuration {
    /// Whole seconds.
    pub sec: u64,
    /// Nanoseconds beyond `sec`.
    pub nsec: u64,
}

impl QosDuration {
    /// rmw's "infinite" (`RMW_DURATION_INFINITE`): what an unset deadline/lifespan/lease means.
    pub const INFINITE: QosDuration = QosDuration {
        sec: 9_223_372_036,
        nsec: 854_775_807,
    };

    /// From a `std` duration (saturating at infinite).
    pub fn from_std(d: std::time::Duration) -> QosDuration {
        if d.as_secs() >= Self::INFINITE.sec {
            return Self::INFINITE;
        }
        QosDuration {
            sec: d.as_secs(),
            nsec: u64::from(d.subsec_nanos()),
        }
    }
}

/// One publisher's offered QoS, as a bag records it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OfferedQos {
    /// `keep_last`, `keep_all`, `system_default` or `unknown` (DDS discovery does not tell a
    /// writer's history, so recordings say `unknown` as rosbag2's do).
    pub history: String,
    /// History depth (0 when `history` is not `keep_last`).
    pub depth: u32,
    /// `reliable` or `best_effort`.
    pub reliability: String,
    /// `volatile` or `transient_local`.
    pub durability: String,
    /// Deadline.
    pub deadline: QosDuration,
    /// Lifespan.
    pub lifespan: QosDuration,
    /// `automatic` or `manual_by_topic`.
    pub liveliness: String,
    /// Liveliness lease.
    pub liveliness_lease_duration: QosDuration,
    /// Always false for ROS topics.
    pub avoid_ros_namespace_conventions: bool,
}

impl OfferedQos {
    /// A discovered writer's profile: reliable or not, latched or not, everything else default.
    pub fn discovered(reliable: bool, transient_local: bool) -> OfferedQos {
        OfferedQos {
            history: "unknown".into(),
            depth: 0,
            reliability: if reliable { "reliable" } else { "best_effort" }.into(),
            durability: if transient_local {
                "transient_local"
            } else {
                "volatile"
            }
            .into(),
            deadline: QosDuration::INFINITE,
            lifespan: QosDuration::INFINITE,
            liveliness: "automatic".into(),
            liveliness_lease_duration: QosDuration::INFINITE,
            avoid_ros_namespace_conventions: false,
        }
    }

    /// Whether this profile offers reliable delivery.
    pub fn is_reliable(&self) -> bool {
        self.reliability == "reliable"
    }

    /// Whether this profile keeps samples for late joiners.
    pub fn is_transient_local(&self) -> bool {
        self.durability == "transient_local"
    }

    fn from_yaml(y: &Yaml) -> Result<OfferedQos, String> {
        let text = |key: &str| -> Result<String, String> {
            match &y[key] {
                Yaml::String(s) => Ok(s.clone()),
                // The integer form of metadata versions 4..8.
                Yaml::Integer(i) => Ok(i.to_string()),
                other => Err(format!(
                    "QoS key `{key}` is missing or not a string: {other:?}"
                )),
            }
        };
        let duration = |key: &str| -> Result<QosDuration, String> {
            let (sec, nsec) = (&y[key]["sec"], &y[key]["nsec"]);
            match (sec.as_i64(), nsec.as_i64()) {
                (Some(s), Some(n)) if s >= 0 && n >= 0 => Ok(QosDuration {
                    sec: s as u64,
                    nsec: n as u64,
                }),
                _ => Err(format!(
                    "QoS key `{key}` needs non-negative `sec` and `nsec`"
                )),
            }
        };
        Ok(OfferedQos {
            history: text("history")?,
            depth: y["depth"].as_i64().unwrap_or(0).max(0) as u32,
            reliability: text("reliability")?,
            durability: text("durability")?,
            deadline: duration("deadline")?,
            lifespan: duration("lifespan")?,
            liveliness: text("liveliness")?,
            liveliness_lease_duration: duration("liveliness_lease_duration")?,
            avoid_ros_namespace_conventions: y["avoid_ros_namespace_conventions"]
                .as_bool()
                .unwrap_or(false),
        })
    }
}

/// A profile list as YAML block text, each line prefixed by `indent` spaces (yaml-cpp's layout:
/// `- history: ...` then the other keys two columns in). An empty list is `[]`.
pub fn profiles_yaml(profiles: &[OfferedQos], indent: usize) -> String {
    let pad = " ".repeat(indent);
    if profiles.is_empty() {
        return format!("{pad}[]");
    }
    let mut out = String::new();
    for p in profiles {
        let duration = |out: &mut String, key: &str, d: QosDuration| {
            let _ = write!(
                out,
                "\n{pad}  {key}:\n{pad}    sec: {}\n{pad}    nsec: {}",
                d.sec, d.nsec
            );
        };
        if !out.is_empty() {
            out.push('\n');
        }
        let _ = write!(
            out,
            "{pad}- history: {}\n{pad}  depth: {}\n{pad}  reliability: {}\n{pad}  durability: {}",
            p.history, p.depth, p.reliability, p.durability
        );
        duration(&mut out, "deadline", p.deadline);
        duration(&mut out, "lifespan", p.lifespan);
        let _ = write!(out, "\n{pad}  liveliness: {}", p.liveliness);
        duration(
            &mut out,
            "liveliness_lease_duration",
            p.liveliness_lease_duration,
        );
        let _ = write!(
            out,
            "\n{pad}  avoid_ros_namespace_conventions: {}",
            p.avoid_ros_namespace_conventions
        );
    }
    out
}

/// Profiles from a YAML node: a list (version 9), or a string holding one (versions 4..8 and
/// MCAP channel metadata).
pub fn profiles_from_yaml(y: &Yaml) -> Result<Vec<OfferedQos>, String> {
    match y {
        Yaml::Array(items) => items.iter().map(OfferedQos::from_yaml).collect(),
        Yaml::String(text) => {
            let docs = yaml_rust2::YamlLoader::load_from_str(text)
                .map_err(|e| format!("offered_qos_profiles is not YAML: {e}"))?;
            match docs.first() {
                Some(doc) => profiles_from_yaml(doc),
                None => Ok(Vec::new()),
            }
        }
        Yaml::Null | Yaml::BadValue => Ok(Vec::new()),
        other => Err(format!(
            "offered_qos_profiles must be a list, found {other:?}"
        )),
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn profiles_round_trip_through_both_yaml_forms() {
        let profiles = vec![
            OfferedQos::discovered(true, false),
            OfferedQos::discovered(false, true),
        ];
        let text = profiles_yaml(&profiles, 0);
        assert!(text.starts_with("- history: unknown\n  depth: 0\n  reliability: reliable\n"));
        assert!(
            !text.ends_with('\n'),
            "channel metadata has no trailing newline"
        );
        let as_string = Yaml::String(text.clone());
        assert_eq!(profiles_from_yaml(&as_string).unwrap(), profiles);
        let indented = profiles_yaml(&profiles, 8);
        let doc = yaml_rust2::YamlLoader::load_from_str(&format!("q:\n{indented}")).unwrap();
        assert_eq!(profiles_from_yaml(&doc[0]["q"]).unwrap(), profiles);
        assert_eq!(profiles_yaml(&[], 4), "    []");
    }

    #[test]
    fn infinite_durations_saturate() {
        let long = std::time::Duration::from_secs(u64::MAX / 2);
        assert_eq!(QosDuration::from_std(long), QosDuration::INFINITE);
        let d = QosDuration::from_std(std::time::Duration::from_millis(1500));
        assert_eq!((d.sec, d.nsec), (1, 500_000_000));
    }
}
