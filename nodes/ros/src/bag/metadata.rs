//! `metadata.yaml`: what a rosbag2 directory says about itself — rosbag2 bagfile information
//! version 9, the layout ROS 2 Jazzy writes (keys in yaml-cpp's order,
//! docs/src/rosbag2-format.md §1). The same text without the top-level wrapper is stored in each
//! MCAP file's `rosbag2` metadata record.

use std::collections::BTreeMap;
use std::fmt::Write;

use yaml_rust2::{Yaml, YamlLoader};

use super::qos::{OfferedQos, profiles_from_yaml, profiles_yaml};

/// The metadata version Jazzy writes.
pub const VERSION: i64 = 9;
/// The storage plugin of every bag this suite writes.
pub const STORAGE_ID: &str = "mcap";
/// `starting_time` of a bag without messages (rosbag2 leaves it at `INT64_MAX`).
pub const NO_START: u64 = i64::MAX as u64;

/// One recorded topic.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// Full topic name (`/env_00/observation`).
    pub name: String,
    /// ROS type (`composuite_msgs/msg/Observation`).
    pub type_name: String,
    /// Always `cdr`.
    pub serialization_format: String,
    /// What the publishers offered when the recorder subscribed.
    pub offered_qos_profiles: Vec<OfferedQos>,
    /// `RIHS01_…`, or empty when unknown.
    pub type_description_hash: String,
    /// Messages recorded on the topic.
    pub message_count: u64,
}

/// One storage file of the bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileInfo {
    /// File name, relative to the bag directory (`session_0.mcap`).
    pub path: String,
    /// Earliest log time in the file (ns since the epoch).
    pub starting_time_ns: u64,
    /// Latest minus earliest log time (ns).
    pub duration_ns: u64,
    /// Messages in the file.
    pub message_count: u64,
}

/// The contents of `metadata.yaml`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagMetadata {
    /// Latest minus earliest log time over the bag (ns).
    pub duration_ns: u64,
    /// Earliest log time (ns since the epoch); [`NO_START`] without messages.
    pub starting_time_ns: u64,
    /// Messages in the bag.
    pub message_count: u64,
    /// Every topic, including those without messages.
    pub topics: Vec<TopicInfo>,
    /// The storage files, in order.
    pub files: Vec<FileInfo>,
    /// User key/values (`custom_data`).
    pub custom_data: BTreeMap<String, String>,
    /// `$ROS_DISTRO` when recording (`jazzy` for this suite).
    pub ros_distro: String,
}

impl BagMetadata {
    /// An empty bag's metadata.
    pub fn empty(ros_distro: &str) -> BagMetadata {
        BagMetadata {
            duration_ns: 0,
            starting_time_ns: NO_START,
            message_count: 0,
            topics: Vec::new(),
            files: Vec::new(),
            custom_data: BTreeMap::new(),
            ros_distro: ros_distro.into(),
        }
    }

    /// The end of the bag (ns since the epoch), when it has messages.
    pub fn end_time_ns(&self) -> Option<u64> {
        (self.message_count > 0).then(|| self.starting_time_ns + self.duration_ns)
    }

    /// `metadata.yaml` text (with the `rosbag2_bagfile_information` wrapper).
    pub fn to_file_yaml(&self) -> String {
        let mut out = String::from("rosbag2_bagfile_information:\n");
        out.push_str(&self.body_yaml(2));
        out
    }

    /// The text of the MCAP `rosbag2` record's `serialized_metadata` (no wrapper).
    pub fn to_record_yaml(&self) -> String {
        self.body_yaml(0)
    }

    fn body_yaml(&self, indent: usize) -> String {
        let p = " ".repeat(indent);
        let mut o = String::new();
        let _ = writeln!(o, "{p}version: {VERSION}");
        let _ = writeln!(o, "{p}storage_identifier: {STORAGE_ID}");
        let _ = writeln!(o, "{p}duration:\n{p}  nanoseconds: {}", self.duration_ns);
        let _ = writeln!(
            o,
            "{p}starting_time:\n{p}  nanoseconds_since_epoch: {}",
            self.starting_time_ns
        );
        let _ = writeln!(o, "{p}message_count: {}", self.message_count);
        if self.topics.is_empty() {
            let _ = writeln!(o, "{p}topics_with_message_count: []");
        } else {
            let _ = writeln!(o, "{p}topics_with_message_count:");
        }
        for t in &self.topics {
            let _ = writeln!(o, "{p}  - topic_metadata:");
            let _ = writeln!(o, "{p}      name: {}", scalar(&t.name));
            let _ = writeln!(o, "{p}      type: {}", scalar(&t.type_name));
            let _ = writeln!(
                o,
                "{p}      serialization_format: {}",
                scalar(&t.serialization_format)
            );
            let _ = writeln!(o, "{p}      offered_qos_profiles:");
            let _ = writeln!(o, "{}", profiles_yaml(&t.offered_qos_profiles, indent + 8));
            let _ = writeln!(
                o,
                "{p}      type_description_hash: {}",
                scalar(&t.type_description_hash)
            );
            let _ = writeln!(o, "{p}    message_count: {}", t.message_count);
        }
        let _ = writeln!(o, "{p}compression_format: \"\"");
        let _ = writeln!(o, "{p}compression_mode: \"\"");
        if self.files.is_empty() {
            let _ = writeln!(o, "{p}relative_file_paths: []\n{p}files: []");
        } else {
            let _ = writeln!(o, "{p}relative_file_paths:");
            for f in &self.files {
                let _ = writeln!(o, "{p}  - {}", scalar(&f.path));
            }
            let _ = writeln!(o, "{p}files:");
            for f in &self.files {
                let _ = writeln!(o, "{p}  - path: {}", scalar(&f.path));
                let _ = writeln!(
                    o,
                    "{p}    starting_time:\n{p}      nanoseconds_since_epoch: {}",
                    f.starting_time_ns
                );
                let _ = writeln!(
                    o,
                    "{p}    duration:\n{p}      nanoseconds: {}",
                    f.duration_ns
                );
                let _ = writeln!(o, "{p}    message_count: {}", f.message_count);
            }
        }
        if self.custom_data.is_empty() {
            let _ = writeln!(o, "{p}custom_data: ~");
        } else {
            let _ = writeln!(o, "{p}custom_data:");
            for (k, v) in &self.custom_data {
                let _ = writeln!(o, "{p}  {}: {}", scalar(k), scalar(v));
            }
        }
        let _ = writeln!(o, "{p}ros_distro: {}", scalar(&self.ros_distro));
        o
    }

    /// Parse `metadata.yaml` text (the wrapped form; the bare record form is accepted too).
    pub fn parse(text: &str) -> Result<BagMetadata, String> {
        let docs = YamlLoader::load_from_str(text).map_err(|e| format!("not YAML: {e}"))?;
        let doc = docs.first().ok_or("empty document")?;
        let info = match &doc["rosbag2_bagfile_information"] {
            Yaml::BadValue => doc,
            wrapped => wrapped,
        };
        let version = info["version"]
            .as_i64()
            .ok_or("`version` is missing or not an integer")?;
        if !(4..=VERSION).contains(&version) {
            return Err(format!(
                "bagfile information version {version} is not supported (4 to {VERSION})"
            ));
        }
        let storage = info["storage_identifier"].as_str().unwrap_or_default();
        if storage != STORAGE_ID {
            return Err(format!(
                "storage `{storage}` is not supported; this tool reads `{STORAGE_ID}` bags"
            ));
        }
        let uint = |y: &Yaml, what: &str| -> Result<u64, String> {
            match y.as_i64() {
                Some(v) if v >= 0 => Ok(v as u64),
                _ => Err(format!("`{what}` is missing or not a non-negative integer")),
            }
        };
        let string = |y: &Yaml| y.as_str().unwrap_or_default().to_string();
        let mut topics = Vec::new();
        for entry in info["topics_with_message_count"]
            .as_vec()
            .unwrap_or(&vec![])
        {
            let t = &entry["topic_metadata"];
            topics.push(TopicInfo {
                name: t["name"].as_str().ok_or("a topic without `name`")?.into(),
                type_name: t["type"].as_str().ok_or("a topic without `type`")?.into(),
                serialization_format: string(&t["serialization_format"]),
                offered_qos_profiles: profiles_from_yaml(&t["offered_qos_profiles"])?,
                type_description_hash: string(&t["type_description_hash"]),
                message_count: uint(&entry["message_count"], "message_count")?,
            });
        }
        let mut files = Vec::new();
        for f in info["files"].as_vec().unwrap_or(&vec![]) {
            files.push(FileInfo {
                path: f["path"].as_str().ok_or("a file without `path`")?.into(),
                starting_time_ns: uint(
                    &f["starting_time"]["nanoseconds_since_epoch"],
                    "files.starting_time",
                )?,
                duration_ns: uint(&f["duration"]["nanoseconds"], "files.duration")?,
                message_count: uint(&f["message_count"], "files.message_count")?,
            });
        }
        // Bags without `files` (versions < 5, or a reindexed bag) still list their paths.
        if files.is_empty() {
            for path in info["relative_file_paths"].as_vec().unwrap_or(&vec![]) {
                files.push(FileInfo {
                    path: string(path),
                    starting_time_ns: 0,
                    duration_ns: 0,
                    message_count: 0,
                });
            }
        }
        let mut custom_data = BTreeMap::new();
        if let Some(map) = info["custom_data"].as_hash() {
            for (k, v) in map {
                custom_data.insert(string(k), string(v));
            }
        }
        Ok(BagMetadata {
            duration_ns: uint(&info["duration"]["nanoseconds"], "duration")?,
            starting_time_ns: uint(
                &info["starting_time"]["nanoseconds_since_epoch"],
                "starting_time",
            )?,
            message_count: uint(&info["message_count"], "message_count")?,
            topics,
            files,
            custom_data,
            ros_distro: string(&info["ros_distro"]),
        })
    }
}

/// A YAML scalar: plain when it is safe to be, else double-quoted (empty strings are `""`, as
/// yaml-cpp writes them).
fn scalar(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_/.-".contains(c))
        && !s.starts_with(['-', '.'])
        && !matches!(s, "true" | "false" | "null" | "~" | "yes" | "no")
        && s.parse::<f64>().is_err();
    if plain {
        s.to_string()
    } else {
        let escaped = s.replace('\\', "\\\\").replace('"', "\\\"");
        format!("\"{escaped}\"")
    }
}

#[cfg(test)]
mod test {
    use super::*;

    fn sample() -> BagMetadata {
        BagMetadata {
            duration_ns: 12_500_000_000,
            starting_time_ns: 1_712_345_678_000_000_000,
            message_count: 3,
            topics: vec![
                TopicInfo {
                    name: "/env_00/observation".into(),
                    type_name: "composuite_msgs/msg/Observation".into(),
                    serialization_format: "cdr".into(),
                    offered_qos_profiles: vec![OfferedQos::discovered(true, false)],
                    type_description_hash: "RIHS01_00ff".into(),
                    message_count: 3,
                },
                TopicInfo {
                    name: "/quiet".into(),
                    type_name: "std_msgs/msg/Bool".into(),
                    serialization_format: "cdr".into(),
                    offered_qos_profiles: vec![],
                    type_description_hash: String::new(),
                    message_count: 0,
                },
            ],
            files: vec![FileInfo {
                path: "run_0.mcap".into(),
                starting_time_ns: 1_712_345_678_000_000_000,
                duration_ns: 12_500_000_000,
                message_count: 3,
            }],
            custom_data: [("seed".to_string(), "7".to_string())].into(),
            ros_distro: "jazzy".into(),
        }
    }

    #[test]
    fn metadata_round_trips_and_keeps_jazzy_key_order() {
        let m = sample();
        let text = m.to_file_yaml();
        assert_eq!(BagMetadata::parse(&text).unwrap(), m);
        assert_eq!(BagMetadata::parse(&m.to_record_yaml()).unwrap(), m);
        let keys: Vec<&str> = text
            .lines()
            .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
            .map(|l| l.trim().split(':').next().unwrap())
            .collect();
        assert_eq!(
            keys,
            [
                "version",
                "storage_identifier",
                "duration",
                "starting_time",
                "message_count",
                "topics_with_message_count",
                "compression_format",
                "compression_mode",
                "relative_file_paths",
                "files",
                "custom_data",
                "ros_distro"
            ]
        );
        assert!(text.contains("type_description_hash: \"\""));
        assert!(text.contains("custom_data:\n    seed: \"7\""));
    }

    #[test]
    fn an_empty_bag_has_no_start() {
        let m = BagMetadata::empty("jazzy");
        let text = m.to_file_yaml();
        assert!(text.contains("nanoseconds_since_epoch: 9223372036854775807"));
        assert!(text.contains("custom_data: ~"));
        assert_eq!(BagMetadata::parse(&text).unwrap(), m);
        assert_eq!(m.end_time_ns(), None);
    }

    #[test]
    fn bad_metadata_is_named() {
        let e = BagMetadata::parse("rosbag2_bagfile_information:\n  version: 10\n").unwrap_err();
        assert!(e.contains("version 10"), "{e}");
        let e = BagMetadata::parse(
            "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: sqlite3\n",
        )
        .unwrap_err();
        assert!(e.contains("sqlite3"), "{e}");
    }
}
