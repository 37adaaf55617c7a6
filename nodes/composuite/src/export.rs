//! `composuite bag export`: chosen topics of a bag as JSON lines or CSV, one file per topic,
//! decoded with the msgs crate's types (every field by its `.msg` name, in name order). A CSV row is
//! one message flattened: nested fields as `a.b`, array elements as `a[i]`.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use composuite_msgs::{MessageVisitor, RosMessage, cdr};
use composuite_ros::bag::reader::{for_each_message, read_metadata};
use serde_json::{Value, json};

/// The output format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// One JSON object per line: {"log_time", "publish_time", "message"}.
    Jsonl,
    /// One row per message, the message flattened into columns.
    Csv,
}

/// Decode `data` (CDR with header) of ROS type `type_name` to JSON; `None` for a type the msgs
/// crate does not have.
fn decode_json(type_name: &str, data: &[u8]) -> Option<Result<Value, String>> {
    struct Decode<'a> {
        name: &'a str,
        data: &'a [u8],
        out: Option<Result<Value, String>>,
    }
    impl MessageVisitor for Decode<'_> {
        fn visit<T: RosMessage>(&mut self) {
            if self.out.is_none() && T::ROS_NAME == self.name {
                self.out = Some(
                    cdr::decode::<T>(self.data)
                        .map_err(|e| e.to_string())
                        .and_then(|m| serde_json::to_value(&m).map_err(|e| e.to_string())),
                );
            }
        }
    }
    let mut visitor = Decode {
        name: type_name,
        data,
        out: None,
    };
    composuite_msgs::visit_messages(&mut visitor);
    visitor.out
}

/// Flatten a JSON value into `prefix`-named columns.
fn flatten(prefix: &str, value: &Value, out: &mut Vec<(String, String)>) {
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                let name = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&name, v, out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                flatten(&format!("{prefix}[{i}]"), v, out);
            }
        }
        Value::String(s) => out.push((prefix.into(), csv_field(s))),
        other => out.push((prefix.into(), other.to_string())),
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.into()
    }
}

struct TopicFile {
    path: PathBuf,
    out: BufWriter<File>,
    header: Option<Vec<String>>,
    count: u64,
    mismatched: u64,
}

/// Export `topics` (all when empty) of `bag` into `out_dir` as `format`.
pub fn run(bag: &Path, topics: &[String], format: Format, out_dir: &Path) -> Result<(), String> {
    let metadata = read_metadata(bag).map_err(|e| e.0)?;
    let known: Vec<&str> = metadata.topics.iter().map(|t| t.name.as_str()).collect();
    for t in topics {
        if !known.contains(&t.as_str()) {
            return Err(format!(
                "topic {t} is not in {}; its topics: {}",
                bag.display(),
                known.join(", ")
            ));
        }
    }
    std::fs::create_dir_all(out_dir)
        .map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let wanted = |topic: &str| topics.is_empty() || topics.iter().any(|t| t == topic);
    let mut files: BTreeMap<String, TopicFile> = BTreeMap::new();
    let mut skipped: BTreeMap<String, String> = BTreeMap::new();
    let extension = match format {
        Format::Jsonl => "jsonl",
        Format::Csv => "csv",
    };
    for_each_message(bag, |m| {
        if !wanted(m.topic) || skipped.contains_key(m.topic) {
            return Ok(());
        }
        let value = match decode_json(m.type_name, m.data) {
            None => {
                skipped.insert(m.topic.into(), m.type_name.into());
                return Ok(());
            }
            Some(v) => v.map_err(|e| format!("{}: {e}", m.topic))?,
        };
        if !files.contains_key(m.topic) {
            let name = format!("{}.{extension}", m.topic.trim_start_matches('/').replace('/', "__"));
            let path = out_dir.join(name);
            let file = File::create_new(&path)
                .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
            files.insert(
                m.topic.into(),
                TopicFile {
                    path,
                    out: BufWriter::new(file),
                    header: None,
                    count: 0,
                    mismatched: 0,
                },
            );
        }
        let f = files.get_mut(m.topic).expect("inserted above");
        let io = |e: std::io::Error| e.to_string();
        match format {
            Format::Jsonl => {
                let line = json!({"log_time": m.log_time, "publish_time": m.publish_time, "message": value});
                writeln!(f.out, "{line}").map_err(io)?;
            }
            Format::Csv => {
                let mut row = vec![
                    ("log_time".to_string(), m.log_time.to_string()),
                    ("publish_time".to_string(), m.publish_time.to_string()),
                ];
                flatten("", &value, &mut row);
                let header = f.header.get_or_insert_with(|| {
                    row.iter().map(|(k, _)| k.clone()).collect::<Vec<_>>()
                });
                if f.count == 0 {
                    writeln!(f.out, "{}", header.join(",")).map_err(io)?;
                }
                let cells: HashMap<&str, &str> =
                    row.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
                if cells.len() != header.len()
                    || header.iter().any(|h| !cells.contains_key(h.as_str()))
                {
                    f.mismatched += 1;
                }
                let line: Vec<&str> = header
                    .iter()
                    .map(|h| cells.get(h.as_str()).copied().unwrap_or(""))
                    .collect();
                writeln!(f.out, "{}", line.join(",")).map_err(io)?;
            }
        }
        f.count += 1;
        Ok(())
    })
    .map_err(|e| e.0)?;
    for (topic, f) in &mut files {
        f.out
            .flush()
            .map_err(|e| format!("cannot write {}: {e}", f.path.display()))?;
        println!("{topic}: {} messages -> {}", f.count, f.path.display());
        if f.mismatched > 0 {
            eprintln!(
                "composuite bag: {topic}: {} messages had other fields than the first (arrays of \
                 another length); their columns follow the first message's header",
                f.mismatched
            );
        }
    }
    for (topic, type_name) in skipped {
        eprintln!("composuite bag: {topic} skipped: type {type_name} is not one this tool decodes");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use composuite_msgs::std_msgs::msg::Header;

    #[test]
    fn messages_decode_by_type_name_and_flatten() {
        let header = Header {
            frame_id: "a,b".into(),
            ..Default::default()
        };
        let bytes = cdr::encode(&header).unwrap();
        let value = decode_json("std_msgs/msg/Header", &bytes).unwrap().unwrap();
        let mut row = Vec::new();
        flatten("", &value, &mut row);
        assert_eq!(
            row,
            [
                ("frame_id".to_string(), "\"a,b\"".to_string()),
                ("stamp.nanosec".to_string(), "0".to_string()),
                ("stamp.sec".to_string(), "0".to_string()),
            ]
        );
        assert!(decode_json("acme/msg/Unknown", &bytes).is_none());
        let mut arrays = Vec::new();
        flatten("q", &json!([1.5, 2]), &mut arrays);
        assert_eq!(arrays[1], ("q[1]".to_string(), "2".to_string()));
    }
}
