//! The `recorder` node: `ros2 bag record -s mcap` for the suite. A plain DDS subscriber — it
//! records what is on the wire, the agent's commands and other nodes' topics included — that
//! writes a rosbag2 directory (see [`crate::bag`]). Topics are chosen as `ros2 bag record`
//! chooses them: all (`all:=true`, topics that appear later too), a list, a regex, minus an
//! exclude regex; hidden topics (a part starting with `_`) only on request.
//!
//! Messages are stored as received: the CDR bytes of the sample, never decoded and encoded
//! again, so the bag holds exactly what the publisher sent.

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;
use std::pin::Pin;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use futures::stream::SelectAll;
use futures::{FutureExt, Stream, StreamExt};
use ros2_client::ParameterValue;
use ros2_client::dds::rustdds::{
    self, QosPolicyBuilder, RepresentationIdentifier, TopicKind, no_key, policy,
};

use crate::bag::definitions::ros_type_name;
use crate::bag::{BagError, BagOptions, BagWriter, OfferedQos, TopicId};
use crate::shared::node::RosNode;
use crate::shared::params::{ParamSpec, any_value};

/// How often the recorder looks for new publishers.
const DISCOVERY_PERIOD: Duration = Duration::from_millis(100);
/// On SIGINT/SIGTERM, the readers are drained until none yields a sample for this long.
const DRAIN_QUIET: Duration = Duration::from_millis(200);
/// Samples a topic's reader holds before the recorder takes them (far more than a lockstep
/// step ever has in flight).
const READER_DEPTH: i32 = 1000;

/// The recorder's parameters (its command line, as `ros2 bag record`'s options).
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "output",
        default: || ParameterValue::String(String::new()),
        description: "bag directory to create (must not exist), like `ros2 bag record -o`",
        check: any_value,
    },
    ParamSpec {
        name: "all",
        default: || ParameterValue::Boolean(false),
        description: "record every topic, including those that appear later (`-a`)",
        check: any_value,
    },
    ParamSpec {
        name: "topics",
        default: || ParameterValue::StringArray(Vec::new()),
        description: "topics to record, e.g. [/env_00/observation, /env_00/reward]",
        check: any_value,
    },
    ParamSpec {
        name: "regex",
        default: || ParameterValue::String(String::new()),
        description: "also record topics whose full name matches this regex (`-e`)",
        check: check_regex,
    },
    ParamSpec {
        name: "exclude_regex",
        default: || ParameterValue::String(String::new()),
        description: "never record topics whose full name matches this regex (`--exclude-regex`)",
        check: check_regex,
    },
    ParamSpec {
        name: "include_hidden",
        default: || ParameterValue::Boolean(false),
        description: "also record hidden topics (a name part starting with `_`)",
        check: any_value,
    },
    ParamSpec {
        name: "max_bag_size",
        default: || ParameterValue::Integer(0),
        description: "start a new file at this many bytes; 0: one file (`--max-bag-size`)",
        check: non_negative,
    },
    ParamSpec {
        name: "max_bag_duration",
        default: || ParameterValue::Double(0.0),
        description: "start a new file after this many seconds; 0: never (`--max-bag-duration`)",
        check: non_negative,
    },
    ParamSpec {
        name: "compression",
        default: || ParameterValue::String("zstd".into()),
        description: "chunk compression: zstd or none",
        check: |v| match v {
            ParameterValue::String(s) if s == "zstd" || s == "none" => Ok(()),
            _ => Err("valid: zstd, none".into()),
        },
    },
    ParamSpec {
        name: "flush_period",
        default: || ParameterValue::Double(1.0),
        description: "seconds between chunk flushes: at most this much is lost to a SIGKILL",
        check: crate::shared::params::positive_number,
    },
];

fn check_regex(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::String(s) => regex::Regex::new(s)
            .map(drop)
            .map_err(|e| format!("not a regex: {e}")),
        _ => Ok(()),
    }
}

fn non_negative(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::Integer(i) if *i >= 0 => Ok(()),
        ParameterValue::Double(d) if d.is_finite() && *d >= 0.0 => Ok(()),
        _ => Err("must be >= 0 (0: no limit)".into()),
    }
}

/// Which topics to record.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Every topic.
    pub all: bool,
    /// These topics (full names).
    pub topics: Vec<String>,
    /// Topics matching this.
    pub regex: Option<regex::Regex>,
    /// Never topics matching this.
    pub exclude: Option<regex::Regex>,
    /// Hidden topics too.
    pub include_hidden: bool,
}

impl Selection {
    /// Whether to record `topic` (a full ROS name).
    pub fn wants(&self, topic: &str) -> bool {
        if self.exclude.as_ref().is_some_and(|r| r.is_match(topic)) {
            return false;
        }
        if self.topics.iter().any(|t| t == topic) {
            return true;
        }
        let hidden = topic.split('/').any(|part| part.starts_with('_'));
        if hidden && !self.include_hidden {
            return false;
        }
        self.all || self.regex.as_ref().is_some_and(|r| r.is_match(topic))
    }
}

/// The recorder's settings, from its parameters.
struct Config {
    output: PathBuf,
    selection: Selection,
    bag: BagOptions,
    flush_period: Duration,
}

impl Config {
    fn from_node(node: &RosNode) -> Result<Config, String> {
        let output = node.param_string("output");
        if output.is_empty() {
            return Err("no bag directory: give one with -p output:=DIR".into());
        }
        let regex = |name: &str| {
            let text = node.param_string(name);
            (!text.is_empty())
                .then(|| regex::Regex::new(&text).map_err(|e| format!("{name}: {e}")))
                .transpose()
        };
        let topics = match node.param("topics") {
            ParameterValue::StringArray(t) => t
                .into_iter()
                .map(|t| {
                    if t.starts_with('/') {
                        t
                    } else {
                        format!("/{t}")
                    }
                })
                .collect(),
            _ => Vec::new(),
        };
        let selection = Selection {
            all: node.param_bool("all"),
            topics,
            regex: regex("regex")?,
            exclude: regex("exclude_regex")?,
            include_hidden: node.param_bool("include_hidden"),
        };
        if !selection.all && selection.topics.is_empty() && selection.regex.is_none() {
            return Err(
                "nothing to record: set -p all:=true, -p topics:=[...] or -p regex:=...".into(),
            );
        }
        Ok(Config {
            output: PathBuf::from(output),
            selection,
            bag: BagOptions {
                compress: node.param_string("compression") == "zstd",
                max_file_size: node.param_i64("max_bag_size") as u64,
                max_file_duration_ns: (node.param_f64("max_bag_duration") * 1e9) as u64,
                ros_distro: std::env::var("ROS_DISTRO").unwrap_or_else(|_| "jazzy".into()),
                ..BagOptions::default()
            },
            flush_period: Duration::from_secs_f64(node.param_f64("flush_period")),
        })
    }
}

/// A received sample: its CDR bytes (with the encapsulation header put back).
pub struct RawSample(Vec<u8>);

/// Keeps a sample's bytes as they came: no decoding.
pub struct RawAdapter;

const RAW_ENCODINGS: [RepresentationIdentifier; 2] = [
    RepresentationIdentifier::CDR_LE,
    RepresentationIdentifier::CDR_BE,
];

impl no_key::DeserializerAdapter<RawSample> for RawAdapter {
    type Error = std::convert::Infallible;
    type Decoded = RawSample;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &RAW_ENCODINGS
    }

    fn transform_decoded(decoded: RawSample) -> RawSample {
        decoded
    }
}

/// The decoder of [`RawAdapter`]: prefixes the payload with its 4-byte encapsulation header.
#[derive(Clone)]
pub struct RawDecoder;

impl<'de> no_key::Decode<'de, RawSample> for RawDecoder {
    type Error = std::convert::Infallible;

    fn decode_bytes(
        self,
        input: &'de [u8],
        encoding: RepresentationIdentifier,
    ) -> Result<RawSample, Self::Error> {
        let mut bytes = Vec::with_capacity(input.len() + 4);
        bytes.extend_from_slice(&encoding.to_bytes());
        bytes.extend_from_slice(&[0, 0]);
        bytes.extend_from_slice(input);
        Ok(RawSample(bytes))
    }
}

impl no_key::DefaultDecoder<RawSample> for RawAdapter {
    type Decoder = RawDecoder;
    const DECODER: RawDecoder = RawDecoder;
}

type SampleStream = Pin<
    Box<
        dyn Stream<
                Item = (
                    TopicId,
                    rustdds::dds::ReadResult<no_key::DataSample<RawSample>>,
                ),
            > + Send,
    >,
>;

/// A topic seen in discovery, with what its publishers offer.
struct Discovered {
    type_name: String,
    profiles: Vec<OfferedQos>,
    type_hash: String,
}

/// Run the recorder until SIGINT/SIGTERM; the bag is complete when this returns Ok.
pub fn run(node: &mut RosNode, signals: async_channel::Receiver<i32>) -> Result<(), String> {
    let config = Config::from_node(node)?;
    let mut bag = BagWriter::create(&config.output, config.bag.clone()).map_err(|e| e.0)?;
    let log = node.log.clone();
    log.info(format!("recording into {}", config.output.display()));
    let participant = node.context.domain_participant();
    let subscriber = participant
        .create_subscriber(&QosPolicyBuilder::new().build())
        .map_err(|e| format!("cannot create a DDS subscriber: {e:?}"))?;
    let mut streams: SelectAll<SampleStream> = SelectAll::new();
    let mut recorded: HashMap<String, TopicId> = HashMap::new();
    let mut skipped: Vec<String> = Vec::new();
    let outcome: Result<(), BagError> = smol::block_on(async {
        let mut discovery = smol::Timer::interval(DISCOVERY_PERIOD);
        let mut flushes = smol::Timer::interval(config.flush_period);
        loop {
            futures::select_biased! {
                signal = signals.recv().fuse() => {
                    log.info(format!("signal {} received, closing the bag", signal.unwrap_or(0)));
                    // What arrived before the signal is still in the readers: take it until
                    // the readers stay quiet for DRAIN_QUIET. (Taking only the streams that are
                    // ready at this instant lost samples whose arrival had not yet woken their
                    // stream: the last command of a session, now and then.)
                    loop {
                        futures::select_biased! {
                            sample = streams.select_next_some() => {
                                write_sample(&mut bag, sample.0, sample.1, &log)?;
                            }
                            _ = futures::FutureExt::fuse(smol::Timer::after(DRAIN_QUIET)) => break,
                        }
                    }
                    return Ok(());
                }
                sample = streams.select_next_some() => {
                    write_sample(&mut bag, sample.0, sample.1, &log)?;
                }
                _ = flushes.next().fuse() => bag.flush()?,
                _ = discovery.next().fuse() => {
                    for (topic, found) in discover(&participant) {
                        if recorded.contains_key(&topic) || skipped.contains(&topic) {
                            continue;
                        }
                        if !config.selection.wants(&topic) {
                            skipped.push(topic);
                            continue;
                        }
                        let id = bag.add_topic(&topic, &found.type_name, found.profiles.clone(), &found.type_hash)?;
                        match subscribe(&participant, &subscriber, &topic, &found, id) {
                            Ok(stream) => {
                                log.info(format!("recording {topic} ({})", found.type_name));
                                streams.push(stream);
                                recorded.insert(topic, id);
                            }
                            Err(e) => {
                                log.error(format!("cannot subscribe to {topic}: {e}"));
                                skipped.push(topic);
                            }
                        }
                    }
                }
            }
        }
    });
    if let Err(e) = outcome {
        // A full disk or a removed directory: say so; what is written stays readable.
        let _ = bag.close();
        return Err(format!("recording stopped: {e}"));
    }
    let metadata = bag.close().map_err(|e| e.0)?;
    log.info(format!(
        "bag {} closed: {} messages on {} topics",
        config.output.display(),
        metadata.message_count,
        metadata.topics.len()
    ));
    Ok(())
}

fn write_sample(
    bag: &mut BagWriter,
    topic: TopicId,
    sample: rustdds::dds::ReadResult<no_key::DataSample<RawSample>>,
    log: &crate::shared::node::Logger,
) -> Result<(), BagError> {
    let sample = match sample {
        Ok(s) => s,
        Err(e) => {
            log.warn(format!("a sample could not be read: {e:?}"));
            return Ok(());
        }
    };
    let log_time = now_ns();
    let publish_time = sample
        .sample_info()
        .source_timestamp()
        .map(rtps_time_ns)
        .unwrap_or(log_time);
    bag.write(topic, log_time, publish_time, &sample.value().0)
}

/// An RTPS timestamp (seconds + 2^-32 fractions since the epoch) in ns since the epoch.
fn rtps_time_ns(t: rustdds::Timestamp) -> u64 {
    let ticks = t.to_ticks();
    (ticks >> 32) * 1_000_000_000 + (((ticks & 0xFFFF_FFFF) * 1_000_000_000) >> 32)
}

fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

/// Every ROS topic with a publisher now (`rt/` DDS topics of ROS-named types), with its type
/// and the QoS each of its publishers offers.
fn discover(participant: &rustdds::DomainParticipant) -> BTreeMap<String, Discovered> {
    let mut topics: BTreeMap<String, Discovered> = BTreeMap::new();
    for writer in participant.discovered_writers() {
        let data = &writer.publication_topic_data;
        let Some(ros_name) = data.topic_name.strip_prefix("rt/") else {
            continue; // services (rq/, rr/) and DDS-internal topics
        };
        let Some(type_name) = ros_type_name(&data.type_name) else {
            continue;
        };
        let reliable = matches!(data.reliability, Some(policy::Reliability::Reliable { .. }));
        let latched = matches!(data.durability, Some(policy::Durability::TransientLocal));
        let entry = topics.entry(format!("/{ros_name}")).or_insert(Discovered {
            type_name,
            profiles: Vec::new(),
            type_hash: String::new(),
        });
        entry
            .profiles
            .push(OfferedQos::discovered(reliable, latched));
        if entry.type_hash.is_empty() {
            entry.type_hash = type_hash_of(&writer.user_data);
        }
    }
    topics
}

/// The `typehash=RIHS01_…;` a Jazzy publisher puts in its USER_DATA.
fn type_hash_of(user_data: &[u8]) -> String {
    let text = String::from_utf8_lossy(user_data);
    text.split(';')
        .find_map(|kv| kv.trim().strip_prefix("typehash="))
        .filter(|h| h.starts_with("RIHS01_"))
        .unwrap_or_default()
        .to_string()
}

/// A reader of `topic` that takes whatever its publishers offer: reliable only when all are,
/// transient-local only when all are (so a latched value already published is recorded), as
/// `ros2 bag record` adapts its QoS.
fn subscribe(
    participant: &rustdds::DomainParticipant,
    subscriber: &rustdds::Subscriber,
    topic: &str,
    found: &Discovered,
    id: TopicId,
) -> Result<SampleStream, String> {
    let reliable = found.profiles.iter().all(OfferedQos::is_reliable);
    let latched = found.profiles.iter().all(OfferedQos::is_transient_local);
    let mut qos = QosPolicyBuilder::new()
        .history(policy::History::KeepLast {
            depth: READER_DEPTH,
        })
        .durability(if latched {
            policy::Durability::TransientLocal
        } else {
            policy::Durability::Volatile
        });
    qos = if reliable {
        qos.reliable(rustdds::Duration::from_millis(100))
    } else {
        qos.best_effort()
    };
    let qos = qos.build();
    let dds_type = found.type_name.replacen("/msg/", "::msg::dds_::", 1) + "_";
    let dds_topic = participant
        .create_topic(format!("rt{topic}"), dds_type, &qos, TopicKind::NoKey)
        .map_err(|e| format!("{e:?}"))?;
    let reader = subscriber
        .create_datareader_no_key::<RawSample, RawAdapter>(&dds_topic, Some(qos))
        .map_err(|e| format!("{e:?}"))?;
    Ok(Box::pin(
        reader.async_sample_stream().map(move |sample| (id, sample)),
    ))
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn selection_follows_ros2_bag_record() {
        let sel = |all, topics: &[&str], regex: &str, exclude: &str| Selection {
            all,
            topics: topics.iter().map(|t| t.to_string()).collect(),
            regex: (!regex.is_empty()).then(|| regex::Regex::new(regex).unwrap()),
            exclude: (!exclude.is_empty()).then(|| regex::Regex::new(exclude).unwrap()),
            include_hidden: false,
        };
        let all = sel(true, &[], "", "");
        assert!(all.wants("/env_00/observation"));
        assert!(
            !all.wants("/_private/x"),
            "hidden topics need include_hidden"
        );
        let listed = sel(false, &["/a", "/_hidden"], "", "");
        assert!(listed.wants("/a") && listed.wants("/_hidden") && !listed.wants("/b"));
        let by_regex = sel(false, &[], "^/env_0[01]/", "reward$");
        assert!(by_regex.wants("/env_01/observation"));
        assert!(!by_regex.wants("/env_02/observation"));
        assert!(!by_regex.wants("/env_00/reward"), "exclude wins");
    }

    #[test]
    fn type_hash_comes_from_user_data() {
        let ud = b"typehash=RIHS01_abc123;";
        assert_eq!(type_hash_of(ud), "RIHS01_abc123");
        assert_eq!(type_hash_of(b""), "");
        assert_eq!(type_hash_of(b"enclave=/;"), "");
    }

    #[test]
    fn rtps_times_convert_to_ns() {
        let t = rustdds::Timestamp::from_ticks((1_700_000_000u64 << 32) | (1 << 31));
        assert_eq!(rtps_time_ns(t), 1_700_000_000_500_000_000);
    }

    #[test]
    fn raw_samples_keep_their_encapsulation() {
        use no_key::Decode;
        let RawSample(bytes) = RawDecoder
            .decode_bytes(&[1, 2, 3], RepresentationIdentifier::CDR_LE)
            .unwrap();
        assert_eq!(bytes, [0, 1, 0, 0, 1, 2, 3]);
    }
}
