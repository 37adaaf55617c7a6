//! Writes a rosbag2 directory the way Jazzy's `ros2 bag record -s mcap` lays it out: MCAP files
//! `<dir name>_<N>.mcap` (profile `ros2`, `ros2msg` schemas, `cdr` messages, zstd chunks with
//! message indexes, summary and CRCs) and `metadata.yaml` at close. Every schema and channel goes
//! into the data section when its topic is added, so a topic without messages still passes
//! `mcap doctor` (docs/src/rosbag2-format.md §6).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use mcap::records::{MessageHeader, Metadata};

use super::definitions;
use super::metadata::{BagMetadata, FileInfo, NO_START, TopicInfo};
use super::qos::{OfferedQos, profiles_yaml};

/// Why writing a bag failed; the text names the file and what went wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagError(pub String);

impl std::fmt::Display for BagError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BagError {}

/// How to write the bag.
#[derive(Debug, Clone)]
pub struct BagOptions {
    /// zstd-compress each chunk.
    pub compress: bool,
    /// Close a chunk once it holds this many uncompressed bytes (rosbag2: 768 KiB).
    pub chunk_size: u64,
    /// Start a new file once the current one reaches this many bytes (0: never), like
    /// `ros2 bag record --max-bag-size`.
    pub max_file_size: u64,
    /// Start a new file once the current one spans this many ns of log time (0: never), like
    /// `--max-bag-duration`.
    pub max_file_duration_ns: u64,
    /// `ros_distro` in the metadata.
    pub ros_distro: String,
    /// `custom_data` in the metadata.
    pub custom_data: BTreeMap<String, String>,
}

impl Default for BagOptions {
    fn default() -> Self {
        BagOptions {
            compress: true,
            chunk_size: 768 * 1024,
            max_file_size: 0,
            max_file_duration_ns: 0,
            ros_distro: "jazzy".into(),
            custom_data: BTreeMap::new(),
        }
    }
}

/// A topic of the bag, by the order it was added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TopicId(pub usize);

/// An open bag directory.
pub struct BagWriter {
    dir: PathBuf,
    stem: String,
    options: BagOptions,
    topics: Vec<TopicInfo>,
    /// The `ros2msg` schema text of each topic, when known.
    definitions: Vec<Option<&'static str>>,
    closed_files: Vec<FileInfo>,
    current: Option<OpenFile>,
    /// Log times only move forward (arrival order), so files are in time order.
    last_log_time: u64,
}

struct OpenFile {
    writer: mcap::Writer<CountingFile>,
    path: PathBuf,
    /// Channel id of each topic in this file.
    channels: Vec<u16>,
    info: FileInfo,
    /// The file's length, shared with its [`CountingFile`] (the writer owns that).
    len: Arc<AtomicU64>,
}

impl BagWriter {
    /// Create the bag directory `dir` (it must not exist, as with `ros2 bag record -o`) and its
    /// first file.
    pub fn create(dir: &Path, options: BagOptions) -> Result<BagWriter, BagError> {
        if dir.exists() {
            return Err(BagError(format!(
                "bag directory {} already exists; give a new directory (a bag is never overwritten)",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(|e| {
            BagError(format!(
                "cannot create bag directory {}: {e}",
                dir.display()
            ))
        })?;
        let stem = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .filter(|n| !n.is_empty() && n != "..")
            .ok_or_else(|| BagError(format!("{} does not name a directory", dir.display())))?;
        let mut bag = BagWriter {
            dir: dir.to_path_buf(),
            stem,
            options,
            topics: Vec::new(),
            definitions: Vec::new(),
            closed_files: Vec::new(),
            current: None,
            last_log_time: 0,
        };
        bag.open_next_file()?;
        Ok(bag)
    }

    /// The bag directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Add a topic (its schema and channel are written at once). `type_hash` is what the
    /// publishers announced (may be empty). The schema holds the msgs crate's definition when
    /// it knows the type *and* the hashes agree; otherwise the schema is empty (as rosbag2
    /// writes a type it has no definition of) — a definition that is not the publisher's would
    /// decode the bytes wrongly.
    pub fn add_topic(
        &mut self,
        name: &str,
        type_name: &str,
        qos: Vec<OfferedQos>,
        type_hash: &str,
    ) -> Result<TopicId, BagError> {
        let known = definitions::lookup(type_name);
        let (hash, definition) = match known {
            Some(d) if type_hash.is_empty() || type_hash == d.type_hash => {
                (d.type_hash.to_string(), Some(d.definition))
            }
            _ => (type_hash.to_string(), None),
        };
        self.definitions.push(definition);
        self.topics.push(TopicInfo {
            name: name.into(),
            type_name: type_name.into(),
            serialization_format: "cdr".into(),
            offered_qos_profiles: qos,
            type_description_hash: hash,
            message_count: 0,
        });
        let id = TopicId(self.topics.len() - 1);
        let topic = self.topics[id.0].clone();
        let file = self
            .current
            .as_mut()
            .expect("a bag always has an open file");
        let channel =
            add_channel(&mut file.writer, &topic, definition).map_err(|e| file.error(e))?;
        file.channels.push(channel);
        Ok(id)
    }

    /// The topics added so far.
    pub fn topics(&self) -> &[TopicInfo] {
        &self.topics
    }

    /// Record one message: `data` is the serialized message with its 4-byte CDR encapsulation
    /// header; `log_time` the receive time, `publish_time` the publisher's source time (ns since
    /// the epoch).
    pub fn write(
        &mut self,
        topic: TopicId,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> Result<(), BagError> {
        let log_time = log_time.max(self.last_log_time);
        self.last_log_time = log_time;
        if self.file_is_full(log_time) {
            self.close_current_file()?;
            self.open_next_file()?;
        }
        let file = self
            .current
            .as_mut()
            .expect("a bag always has an open file");
        let header = MessageHeader {
            channel_id: file.channels[topic.0],
            sequence: 0,
            log_time,
            publish_time,
        };
        file.writer
            .write_to_known_channel(&header, data)
            .map_err(|e| file.error(e))?;
        let info = &mut file.info;
        if info.message_count == 0 {
            info.starting_time_ns = log_time;
        }
        info.duration_ns = log_time - info.starting_time_ns;
        info.message_count += 1;
        self.topics[topic.0].message_count += 1;
        Ok(())
    }

    /// End the current chunk and hand it to the OS: what was written so far survives a SIGKILL.
    pub fn flush(&mut self) -> Result<(), BagError> {
        if let Some(file) = self.current.as_mut() {
            file.writer.flush().map_err(|e| file.error(e))?;
        }
        Ok(())
    }

    /// The bag's metadata as it stands.
    pub fn metadata(&self) -> BagMetadata {
        let mut files = self.closed_files.clone();
        if let Some(f) = &self.current {
            files.push(f.info.clone());
        }
        bag_metadata(&self.topics, files, &self.options)
    }

    /// Finish the files and write `metadata.yaml`.
    pub fn close(mut self) -> Result<BagMetadata, BagError> {
        self.close_current_file()?;
        let metadata = bag_metadata(&self.topics, self.closed_files.clone(), &self.options);
        write_metadata_file(&self.dir, &metadata)?;
        Ok(metadata)
    }

    fn file_is_full(&self, log_time: u64) -> bool {
        let Some(file) = &self.current else {
            return false;
        };
        if file.info.message_count == 0 {
            return false;
        }
        let size = self.options.max_file_size;
        let span = self.options.max_file_duration_ns;
        (size > 0 && file.writer_size() >= size)
            || (span > 0 && log_time - file.info.starting_time_ns >= span)
    }

    fn open_next_file(&mut self) -> Result<(), BagError> {
        let index = self.closed_files.len();
        let name = format!("{}_{index}.mcap", self.stem);
        let path = self.dir.join(&name);
        let io_error = |e: io::Error| BagError(format!("cannot write {}: {e}", path.display()));
        let file = File::create_new(&path).map_err(io_error)?;
        let options = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!("composuite_ros {}", env!("CARGO_PKG_VERSION")))
            .compression(self.options.compress.then_some(mcap::Compression::Zstd))
            // Compress on the recorder's own thread: it has cores to share with the sim.
            .compression_threads(0)
            .chunk_size(Some(self.options.chunk_size));
        let sink = CountingFile::new(file);
        let len = Arc::clone(&sink.len);
        let mut writer = options
            .create(sink)
            .map_err(|e| BagError(format!("cannot write {}: {e}", path.display())))?;
        let mut open = OpenFile {
            len,
            path: path.clone(),
            channels: Vec::new(),
            info: FileInfo {
                path: name,
                starting_time_ns: NO_START,
                duration_ns: 0,
                message_count: 0,
            },
            writer: {
                // rosbag2 writes its metadata record first (zero counts), and again at close.
                let start = bag_metadata(&self.topics, Vec::new(), &self.options);
                writer
                    .write_metadata(&rosbag2_record(&start))
                    .map_err(|e| BagError(format!("cannot write {}: {e}", path.display())))?;
                writer
            },
        };
        for (topic, definition) in self.topics.iter().zip(&self.definitions) {
            let channel =
                add_channel(&mut open.writer, topic, *definition).map_err(|e| open.error(e))?;
            open.channels.push(channel);
        }
        // The header and schemas are on disk before the first message.
        open.writer.flush().map_err(|e| open.error(e))?;
        self.current = Some(open);
        Ok(())
    }

    fn close_current_file(&mut self) -> Result<(), BagError> {
        let Some(mut file) = self.current.take() else {
            return Ok(());
        };
        let mut files = self.closed_files.clone();
        files.push(file.info.clone());
        let metadata = bag_metadata(&self.topics, files, &self.options);
        file.writer
            .write_metadata(&rosbag2_record(&metadata))
            .map_err(|e| file.error(e))?;
        file.writer.finish().map_err(|e| file.error(e))?;
        file.writer
            .into_inner()
            .finish()
            .map_err(|e| BagError(format!("cannot write {}: {e}", file.path.display())))?;
        self.closed_files.push(file.info);
        Ok(())
    }
}

impl OpenFile {
    fn error(&self, e: mcap::McapError) -> BagError {
        BagError(format!("cannot write {}: {e}", self.path.display()))
    }

    /// Bytes written to the file so far (what `max_file_size` limits).
    fn writer_size(&self) -> u64 {
        self.len.load(Ordering::Relaxed)
    }
}

fn add_channel(
    writer: &mut mcap::Writer<CountingFile>,
    topic: &TopicInfo,
    definition: Option<&str>,
) -> Result<u16, mcap::McapError> {
    let (encoding, text) = match definition {
        Some(d) => ("ros2msg", d),
        // rosbag2's choice for a type it has no definition of: an empty schema.
        None => ("", ""),
    };
    let schema = writer.add_schema(&topic.type_name, encoding, text.as_bytes())?;
    let metadata = BTreeMap::from([
        (
            "offered_qos_profiles".to_string(),
            profiles_yaml(&topic.offered_qos_profiles, 0),
        ),
        (
            "topic_type_hash".to_string(),
            topic.type_description_hash.clone(),
        ),
    ]);
    writer.add_channel(schema, &topic.name, "cdr", &metadata)
}

fn rosbag2_record(metadata: &BagMetadata) -> Metadata {
    Metadata {
        name: "rosbag2".into(),
        metadata: BTreeMap::from([("serialized_metadata".to_string(), metadata.to_record_yaml())]),
    }
}

/// The bag's metadata from its topics and files.
pub fn bag_metadata(
    topics: &[TopicInfo],
    files: Vec<FileInfo>,
    options: &BagOptions,
) -> BagMetadata {
    let mut metadata = BagMetadata::empty(&options.ros_distro);
    metadata.custom_data = options.custom_data.clone();
    metadata.topics = topics.to_vec();
    metadata.message_count = files.iter().map(|f| f.message_count).sum();
    let spans = files
        .iter()
        .filter(|f| f.message_count > 0)
        .map(|f| (f.starting_time_ns, f.starting_time_ns + f.duration_ns));
    if let Some((start, end)) = spans.reduce(|(a, b), (c, d)| (a.min(c), b.max(d))) {
        metadata.starting_time_ns = start;
        metadata.duration_ns = end - start;
    }
    metadata.files = files;
    metadata
}

/// Write `metadata.yaml` into `dir` (through a temporary file, so a reader never sees half of
/// it).
pub fn write_metadata_file(dir: &Path, metadata: &BagMetadata) -> Result<(), BagError> {
    let path = dir.join("metadata.yaml");
    let tmp = dir.join(".metadata.yaml.tmp");
    std::fs::write(&tmp, metadata.to_file_yaml())
        .and_then(|()| std::fs::rename(&tmp, &path))
        .map_err(|e| BagError(format!("cannot write {}: {e}", path.display())))
}

/// A buffered file that knows how long it is (for `max_file_size`).
pub struct CountingFile {
    inner: BufWriter<File>,
    position: u64,
    len: Arc<AtomicU64>,
}

impl CountingFile {
    fn new(file: File) -> CountingFile {
        CountingFile {
            inner: BufWriter::with_capacity(64 * 1024, file),
            position: 0,
            len: Arc::new(AtomicU64::new(0)),
        }
    }

    fn finish(mut self) -> io::Result<()> {
        self.inner.flush()?;
        self.inner.get_ref().sync_data()
    }
}

impl Write for CountingFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.position += n as u64;
        self.len.fetch_max(self.position, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

impl Seek for CountingFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.position = self.inner.seek(pos)?;
        self.len.fetch_max(self.position, Ordering::Relaxed);
        Ok(self.position)
    }
}
