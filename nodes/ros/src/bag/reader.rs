//! Reading a bag back: its messages in file order, and `reindex` — `metadata.yaml` rebuilt from
//! the MCAP files alone (as `ros2 bag reindex` does), after restoring the summary and indexes of
//! a file whose writer was killed (as `mcap recover` does: every complete chunk is kept).

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::path::{Path, PathBuf};

use mcap::read::{ChunkFlattener, Options};
use mcap::records::{MessageHeader, Record};

use super::metadata::{BagMetadata, FileInfo, NO_START, TopicInfo};
use super::qos::profiles_from_yaml;
use super::writer::{BagError, BagOptions, bag_metadata, write_metadata_file};

/// One recorded message, as the reader hands it out.
#[derive(Debug)]
pub struct RecordedMessage<'a> {
    /// Topic name.
    pub topic: &'a str,
    /// ROS type (the schema name).
    pub type_name: &'a str,
    /// Receive time, ns since the epoch.
    pub log_time: u64,
    /// Publisher's time, ns since the epoch.
    pub publish_time: u64,
    /// CDR bytes with the encapsulation header.
    pub data: &'a [u8],
}

impl RecordedMessage<'_> {
    /// The message decoded as `T`; an error names the topic (`/env_00/scene: ...`).
    pub fn decode<T: composuite_msgs::RosMessage>(&self) -> Result<T, String> {
        composuite_msgs::cdr::decode(self.data).map_err(|e| format!("{}: {e}", self.topic))
    }
}

/// The storage files of a bag: from `metadata.yaml` when there is one, else every
/// `<name>_<N>.mcap` in numeric order (rosbag2's naming).
pub fn data_files(dir: &Path) -> Result<Vec<PathBuf>, BagError> {
    match read_metadata(dir) {
        Ok(metadata) => Ok(metadata.files.iter().map(|f| dir.join(&f.path)).collect()),
        Err(_) => numbered_files(dir),
    }
}

/// Every `<name>_<N>.mcap` of `dir` in numeric order, whatever `metadata.yaml` says.
fn numbered_files(dir: &Path) -> Result<Vec<PathBuf>, BagError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| BagError(format!("cannot read bag directory {}: {e}", dir.display())))?;
    let mut numbered = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let index = name
            .strip_suffix(".mcap")
            .and_then(|stem| stem.rsplit_once('_'))
            .and_then(|(_, n)| n.parse::<u64>().ok());
        if let Some(index) = index {
            numbered.push((index, entry.path()));
        }
    }
    numbered.sort();
    if numbered.is_empty() {
        return Err(BagError(format!(
            "{} holds no <name>_<N>.mcap files: not a bag directory",
            dir.display()
        )));
    }
    Ok(numbered.into_iter().map(|(_, p)| p).collect())
}

/// Parse `dir/metadata.yaml`.
pub fn read_metadata(dir: &Path) -> Result<BagMetadata, BagError> {
    let path = dir.join("metadata.yaml");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        BagError(format!(
            "cannot read {}: {e} (a bag whose recorder was killed has none: \
             `composuite bag reindex {}` rebuilds it)",
            path.display(),
            dir.display()
        ))
    })?;
    BagMetadata::parse(&text).map_err(|e| BagError(format!("{}: {e}", path.display())))
}

/// Call `each` for every message of the bag in file order. Returns the files that ended early
/// (killed writer) with what stopped the reading; their complete chunks were read.
pub fn for_each_message(
    dir: &Path,
    mut each: impl FnMut(RecordedMessage<'_>) -> Result<(), String>,
) -> Result<Vec<(PathBuf, String)>, BagError> {
    let mut truncated = Vec::new();
    for path in data_files(dir)? {
        let map = map_file(&path)?;
        let scan = scan(&map, |channel, header, data| {
            each(RecordedMessage {
                topic: &channel.topic,
                type_name: &channel.type_name,
                log_time: header.log_time,
                publish_time: header.publish_time,
                data,
            })
        })
        .map_err(|e| BagError(format!("{}: {e}", path.display())))?;
        if let Some(why) = scan.stopped {
            truncated.push((path, why));
        }
    }
    Ok(truncated)
}

/// What `reindex` did.
#[derive(Debug)]
pub struct ReindexReport {
    /// The metadata written.
    pub metadata: BagMetadata,
    /// Files that had no summary (writer killed), rewritten with what they held, and why their
    /// reading stopped.
    pub recovered: Vec<(PathBuf, String)>,
}

/// Rebuild `metadata.yaml` from the bag's MCAP files; first restore the summary and indexes of
/// any file that lacks them.
pub fn reindex(dir: &Path) -> Result<ReindexReport, BagError> {
    // The files on disk, not an old metadata.yaml's list: that may be what is wrong.
    let files = numbered_files(dir)?;
    let mut recovered = Vec::new();
    let mut topics: Vec<TopicInfo> = Vec::new();
    let mut infos = Vec::new();
    let mut ros_distro = String::new();
    let mut custom_data = BTreeMap::new();
    for path in files {
        let mut map = map_file(&path)?;
        if !has_summary(&map) {
            drop(map);
            let why = recover_file(&path)?;
            recovered.push((path.clone(), why));
            map = map_file(&path)?;
        }
        let mut counts: HashMap<u16, u64> = HashMap::new();
        let mut span: Option<(u64, u64)> = None;
        let scan = scan(&map, |channel, header, _| {
            *counts.entry(channel.id).or_default() += 1;
            let t = header.log_time;
            span = Some(span.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
            Ok(())
        })
        .map_err(|e| BagError(format!("{}: {e}", path.display())))?;
        for channel in scan.channels.values() {
            let count = counts.get(&channel.id).copied().unwrap_or(0);
            match topics.iter_mut().find(|t| t.name == channel.topic) {
                Some(t) => t.message_count += count,
                None => topics.push(TopicInfo {
                    name: channel.topic.clone(),
                    type_name: channel.type_name.clone(),
                    serialization_format: channel.encoding.clone(),
                    offered_qos_profiles: channel.qos.clone(),
                    type_description_hash: channel.type_hash.clone(),
                    message_count: count,
                }),
            }
        }
        if let Some(text) = &scan.rosbag2_record
            && let Ok(m) = BagMetadata::parse(text)
        {
            ros_distro = m.ros_distro;
            custom_data = m.custom_data;
        }
        let (start, end) = span.unwrap_or((NO_START, NO_START));
        infos.push(FileInfo {
            path: path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            starting_time_ns: start,
            duration_ns: end - start,
            message_count: counts.values().sum(),
        });
    }
    let options = BagOptions {
        ros_distro,
        custom_data,
        ..BagOptions::default()
    };
    let metadata = bag_metadata(&topics, infos, &options);
    write_metadata_file(dir, &metadata)?;
    Ok(ReindexReport {
        metadata,
        recovered,
    })
}

/// A channel as the scan saw it, with its schema's name.
#[derive(Debug, Clone)]
pub struct ScannedChannel {
    /// Channel id in its file.
    pub id: u16,
    /// Topic name.
    pub topic: String,
    /// Schema name (the ROS type).
    pub type_name: String,
    /// Message encoding (`cdr`).
    pub encoding: String,
    /// `offered_qos_profiles` of the channel metadata.
    pub qos: Vec<super::OfferedQos>,
    /// `topic_type_hash` of the channel metadata.
    pub type_hash: String,
}

struct Scan {
    channels: BTreeMap<u16, ScannedChannel>,
    rosbag2_record: Option<String>,
    /// Why reading stopped before the end of the file (a killed writer), if it did.
    stopped: Option<String>,
}

/// Walk every record of a file (chunks opened), handing out messages; stops quietly at the first
/// record that is cut off or damaged and says why in `stopped`.
fn scan(
    buf: &[u8],
    mut each: impl FnMut(&ScannedChannel, &MessageHeader, &[u8]) -> Result<(), String>,
) -> Result<Scan, String> {
    let mut schemas: HashMap<u16, String> = HashMap::new();
    let mut out = Scan {
        channels: BTreeMap::new(),
        rosbag2_record: None,
        stopped: None,
    };
    let records = ChunkFlattener::new_with_options(buf, Options::IgnoreEndMagic.into())
        .map_err(|e| format!("not an MCAP file: {e}"))?;
    for record in records {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                out.stopped = Some(e.to_string());
                break;
            }
        };
        match record {
            Record::Schema { header, .. } => {
                schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                let meta = |k: &str| c.metadata.get(k).cloned().unwrap_or_default();
                let qos_text = meta("offered_qos_profiles");
                let qos =
                    profiles_from_yaml(&yaml_rust2::Yaml::String(qos_text)).unwrap_or_default();
                out.channels.insert(
                    c.id,
                    ScannedChannel {
                        id: c.id,
                        type_name: schemas.get(&c.schema_id).cloned().unwrap_or_default(),
                        topic: c.topic.clone(),
                        encoding: c.message_encoding.clone(),
                        qos,
                        type_hash: meta("topic_type_hash"),
                    },
                );
            }
            Record::Message { header, data } => {
                let channel = out.channels.get(&header.channel_id).ok_or_else(|| {
                    format!(
                        "a message on channel {} before its channel record",
                        header.channel_id
                    )
                })?;
                each(channel, &header, &data)?;
            }
            Record::Metadata(m) if m.name == "rosbag2" => {
                out.rosbag2_record = m.metadata.get("serialized_metadata").cloned();
            }
            Record::DataEnd(_) => break,
            _ => {}
        }
    }
    Ok(out)
}

fn has_summary(buf: &[u8]) -> bool {
    matches!(mcap::read::Summary::read(buf), Ok(Some(_)))
}

/// Rewrite a file that has no summary (its writer was killed) from its readable records: the
/// same schemas, channels, messages and metadata, then a complete summary. Says why the original
/// stopped.
fn recover_file(path: &Path) -> Result<String, BagError> {
    let tmp = path.with_extension("mcap.recovering");
    let error = |e: &dyn std::fmt::Display| BagError(format!("recovering {}: {e}", path.display()));
    let map = map_file(path)?;
    let sink = std::io::BufWriter::new(File::create(&tmp).map_err(|e| error(&e))?);
    let mut writer = mcap::WriteOptions::new()
        .profile("ros2")
        .library(format!(
            "composuite_ros {} (reindex)",
            env!("CARGO_PKG_VERSION")
        ))
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(sink)
        .map_err(|e| error(&e))?;
    let mut stopped = String::from("the file ended without a summary");
    let records = ChunkFlattener::new_with_options(&map, Options::IgnoreEndMagic.into())
        .map_err(|e| error(&e))?;
    for record in records {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                stopped = e.to_string();
                break;
            }
        };
        let written = match record {
            Record::Schema { header, data } => writer
                .add_schema_with_id(header.id, &header.name, &header.encoding, &data)
                .map(drop),
            Record::Channel(c) => writer
                .add_channel_with_id(
                    c.id,
                    c.schema_id,
                    &c.topic,
                    &c.message_encoding,
                    &c.metadata,
                )
                .map(drop),
            Record::Message { header, data } => writer.write_to_known_channel(&header, &data),
            Record::Metadata(m) => writer.write_metadata(&m),
            Record::DataEnd(_) => break,
            _ => Ok(()),
        };
        written.map_err(|e| error(&e))?;
    }
    writer.finish().map_err(|e| error(&e))?;
    drop(writer);
    drop(map);
    std::fs::rename(&tmp, path).map_err(|e| error(&e))?;
    Ok(stopped)
}

fn map_file(path: &Path) -> Result<memmap2::Mmap, BagError> {
    let file =
        File::open(path).map_err(|e| BagError(format!("cannot open {}: {e}", path.display())))?;
    // Safety: bag files are only read here; a file changed underneath would give wrong bytes,
    // which the MCAP parser reports as an error, not undefined behaviour in our code.
    unsafe { memmap2::Mmap::map(&file) }
        .map_err(|e| BagError(format!("cannot map {}: {e}", path.display())))
}
