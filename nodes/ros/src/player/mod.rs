//! Playing a bag back into a running ROS graph, as `ros2 bag play` does: every recorded message
//! is published again on its topic, as the bytes that were recorded, with the QoS its
//! publishers offered, at the recorded pace scaled by a rate; optionally with a `/clock` that
//! follows the bag's time. Subscribers cannot tell the player from the original publishers
//! (same DDS topic and type names, same reliability and durability).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use bytes::Bytes;
use ros2_client::dds::rustdds::{
    self, QosPolicyBuilder, RepresentationIdentifier, TopicKind, no_key, policy,
};

use crate::bag::OfferedQos;
use crate::bag::metadata::TopicInfo;
use crate::bag::reader::{RecordedMessage, for_each_message, read_metadata};

/// How to play a bag.
#[derive(Debug, Clone, PartialEq)]
pub struct PlayOptions {
    /// Speed factor: 2 plays twice as fast as recorded, 0.5 half as fast.
    pub rate: f64,
    /// Topics to play (full names); empty: every topic of the bag.
    pub topics: Vec<String>,
    /// Publish `/clock` at this rate (Hz) with the bag's time (`ros2 bag play --clock`); the
    /// bag's own `/clock`, if it recorded one, is then not played.
    pub clock_hz: Option<f64>,
    /// Publish topic `.0` of the bag as `.1` (`ros2 bag play --remap FROM:=TO`).
    pub remaps: Vec<(String, String)>,
    /// Wait this long after creating the publishers before the first message, so subscribers
    /// have discovered them (volatile messages sent before a subscriber matched never reach it).
    pub delay: Duration,
}

impl Default for PlayOptions {
    fn default() -> Self {
        PlayOptions {
            rate: 1.0,
            topics: Vec::new(),
            clock_hz: None,
            remaps: Vec::new(),
            delay: Duration::from_secs(1),
        }
    }
}

/// What a play did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlayReport {
    /// Messages published, per topic.
    pub published: BTreeMap<String, u64>,
    /// `/clock` messages published (with `clock_hz`).
    pub clock_ticks: u64,
    /// Wall time from the first message to the last.
    pub wall: Duration,
    /// Bag time from the first message to the last.
    pub bag_span: Duration,
    /// Stopped early by a signal.
    pub interrupted: bool,
}

/// Where a play is, for progress output.
#[derive(Debug, Clone, Copy)]
pub struct PlayProgress {
    /// Messages published so far.
    pub published: u64,
    /// Messages to publish in all.
    pub total: u64,
    /// Bag time played so far (since the first message).
    pub bag_time: Duration,
}

/// The encapsulation header of little-endian plain CDR, what every ROS 2 RMW writes.
const CDR_LE_HEADER: [u8; 2] = [0x00, 0x01];
/// The history depth of a topic whose recording does not tell it (discovery never does).
const DEFAULT_DEPTH: i32 = 10;

/// A recorded message's CDR payload, without its encapsulation header (rustdds writes that).
#[derive(Debug)]
struct Payload(Bytes);

/// Writes a [`Payload`] as it is.
struct PayloadAdapter;

impl no_key::SerializerAdapter<Payload> for PayloadAdapter {
    type Error = std::convert::Infallible;

    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }

    fn to_bytes(value: &Payload) -> Result<Bytes, Self::Error> {
        Ok(value.0.clone())
    }
}

type PayloadWriter = no_key::DataWriter<Payload, PayloadAdapter>;

/// The topics to play: `wanted` (every topic when empty), each of which must be in the bag.
pub fn select_topics<'a>(
    recorded: &'a [TopicInfo],
    wanted: &[String],
) -> Result<Vec<&'a TopicInfo>, String> {
    for name in wanted {
        if !recorded.iter().any(|t| &t.name == name) {
            let names: Vec<&str> = recorded.iter().map(|t| t.name.as_str()).collect();
            return Err(format!(
                "topic {name} is not in the bag; its topics: {}",
                names.join(", ")
            ));
        }
    }
    Ok(recorded
        .iter()
        .filter(|t| wanted.is_empty() || wanted.contains(&t.name))
        .collect())
}

/// `FROM:=TO` as a pair of full topic names.
pub fn parse_remap(text: &str) -> Result<(String, String), String> {
    match text.split_once(":=") {
        Some((from, to)) if from.starts_with('/') && to.starts_with('/') && to.len() > 1 => {
            Ok((from.to_string(), to.to_string()))
        }
        _ => Err(format!(
            "remap `{text}` is invalid: FROM:=TO with full topic names, e.g. /env_00/tf:=/tf"
        )),
    }
}

/// The QoS to publish a recorded topic with: reliable and transient local only when every
/// recorded publisher offered it (so no subscriber that matched the originals is refused), the
/// recorded depth where there is one.
pub fn replay_qos(profiles: &[OfferedQos]) -> rustdds::QosPolicies {
    let all = |f: fn(&OfferedQos) -> bool| !profiles.is_empty() && profiles.iter().all(f);
    let depth = profiles
        .iter()
        .filter(|p| p.history == "keep_last" && p.depth > 0)
        .map(|p| p.depth as i32)
        .max()
        .unwrap_or(DEFAULT_DEPTH);
    let builder = QosPolicyBuilder::new()
        .history(policy::History::KeepLast { depth })
        .durability(if all(OfferedQos::is_transient_local) {
            policy::Durability::TransientLocal
        } else {
            policy::Durability::Volatile
        });
    let builder = if all(OfferedQos::is_reliable) {
        builder.reliable(rustdds::Duration::from_millis(100))
    } else {
        builder.best_effort()
    };
    builder.build()
}

/// The DDS name of a ROS message type (`pkg/msg/Name` → `pkg::msg::dds_::Name_`).
fn dds_type_name(ros_type: &str) -> String {
    ros_type.replacen("/msg/", "::msg::dds_::", 1) + "_"
}

/// When a message recorded at `log_time` is due, counted from the first message.
fn due_after(log_time: u64, first: u64, rate: f64) -> Duration {
    Duration::from_secs_f64(log_time.saturating_sub(first) as f64 * 1e-9 / rate)
}

/// Play `bag` into the graph of `participant`. `clock` publishes one `/clock` value (ns since
/// the epoch; needed with `options.clock_hz`); `stop` says whether to stop early (a signal);
/// `progress` is called after every message.
pub fn play(
    participant: &rustdds::DomainParticipant,
    bag: &Path,
    options: &PlayOptions,
    mut clock: Option<&mut dyn FnMut(u64)>,
    stop: &dyn Fn() -> bool,
    mut progress: impl FnMut(PlayProgress),
) -> Result<PlayReport, String> {
    if !(options.rate.is_finite() && options.rate > 0.0) {
        return Err(format!(
            "rate {} is invalid: a speed factor > 0 (1 = as recorded)",
            options.rate
        ));
    }
    if let Some(hz) = options.clock_hz
        && !(hz.is_finite() && hz > 0.0)
    {
        return Err(format!("clock rate {hz} Hz is invalid: a rate > 0"));
    }
    let metadata = read_metadata(bag).map_err(|e| e.0)?;
    let mut topics = select_topics(&metadata.topics, &options.topics)?;
    let remapped: Vec<String> = options
        .remaps
        .iter()
        .map(|(from, _)| from.clone())
        .collect();
    select_topics(&metadata.topics, &remapped)?;
    if options.clock_hz.is_some() {
        // One clock at a time: the generated one replaces a recorded root `/clock`.
        topics.retain(|t| t.name != "/clock");
    }
    let publisher = participant
        .create_publisher(&QosPolicyBuilder::new().build())
        .map_err(|e| format!("cannot create a DDS publisher: {e:?}"))?;
    let mut writers: BTreeMap<&str, PayloadWriter> = BTreeMap::new();
    for topic in &topics {
        let qos = replay_qos(&topic.offered_qos_profiles);
        let name = options
            .remaps
            .iter()
            .find(|(from, _)| from == &topic.name)
            .map_or(&topic.name, |(_, to)| to);
        let dds_topic = participant
            .create_topic(
                format!("rt{name}"),
                dds_type_name(&topic.type_name),
                &qos,
                TopicKind::NoKey,
            )
            .map_err(|e| format!("cannot create topic {}: {e:?}", topic.name))?;
        let writer = publisher
            .create_datawriter_no_key::<Payload, PayloadAdapter>(&dds_topic, Some(qos))
            .map_err(|e| format!("cannot publish {}: {e:?}", topic.name))?;
        writers.insert(topic.name.as_str(), writer);
    }
    let total: u64 = topics.iter().map(|t| t.message_count).sum();
    std::thread::sleep(options.delay);

    let mut report = PlayReport::default();
    let tick = options.clock_hz.map(|hz| Duration::from_secs_f64(1.0 / hz));
    let mut next_tick = Duration::ZERO;
    let mut first: Option<(u64, Instant)> = None;
    let mut last_log_time = 0u64;
    let truncated = for_each_message(bag, |message: RecordedMessage<'_>| {
        let Some(writer) = writers.get(message.topic) else {
            return Ok(());
        };
        if stop() {
            report.interrupted = true;
            return Err("interrupted".into());
        }
        let (start_log, start_wall) = *first.get_or_insert((message.log_time, Instant::now()));
        let due = due_after(message.log_time, start_log, options.rate);
        // The clock ticks that fall before this message, each carrying the bag time it stands for.
        if let (Some(tick), Some(publish_clock)) = (tick, clock.as_deref_mut()) {
            while next_tick <= due {
                sleep_until(start_wall + next_tick);
                let bag_ns = start_log + (next_tick.as_secs_f64() * options.rate * 1e9) as u64;
                publish_clock(bag_ns);
                report.clock_ticks += 1;
                next_tick += tick;
            }
        }
        sleep_until(start_wall + due);
        let data = message.data;
        if data.len() < 4 || data[..2] != CDR_LE_HEADER {
            return Err(format!(
                "a message on {} is not little-endian CDR (encapsulation {:02x?}); \
                 only that can be played",
                message.topic,
                &data[..data.len().min(2)]
            ));
        }
        writer
            .write(Payload(Bytes::copy_from_slice(&data[4..])), None)
            .map_err(|e| format!("cannot publish on {}: {e:?}", message.topic))?;
        *report
            .published
            .entry(message.topic.to_string())
            .or_default() += 1;
        last_log_time = last_log_time.max(message.log_time);
        progress(PlayProgress {
            published: report.published.values().sum(),
            total,
            bag_time: Duration::from_nanos(last_log_time - start_log),
        });
        Ok(())
    });
    match truncated {
        Ok(files) => {
            if let Some((file, why)) = files.first() {
                return Err(format!(
                    "{} ends early ({why}): play what it holds after `composuite bag reindex`",
                    file.display()
                ));
            }
        }
        Err(_) if report.interrupted => {}
        Err(e) => return Err(e.0),
    }
    if let Some((start_log, start_wall)) = first {
        report.wall = start_wall.elapsed();
        report.bag_span = Duration::from_nanos(last_log_time - start_log);
    }
    // Reliable subscribers get the last messages before the writers go away.
    for writer in writers.values() {
        let _ = writer.wait_for_acknowledgments(Duration::from_secs(2));
    }
    Ok(report)
}

fn sleep_until(when: Instant) {
    let now = Instant::now();
    if when > now {
        std::thread::sleep(when - now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(name: &str) -> TopicInfo {
        TopicInfo {
            name: name.into(),
            type_name: "std_msgs/msg/String".into(),
            serialization_format: "cdr".into(),
            offered_qos_profiles: vec![],
            type_description_hash: String::new(),
            message_count: 1,
        }
    }

    #[test]
    fn unknown_topics_are_named_with_the_bags_topics() {
        let recorded = [topic("/a"), topic("/b")];
        assert_eq!(select_topics(&recorded, &[]).unwrap().len(), 2);
        let picked = select_topics(&recorded, &["/b".to_string()]).unwrap();
        assert_eq!(picked[0].name, "/b");
        let err = select_topics(&recorded, &["/c".to_string()]).unwrap_err();
        assert!(
            err.contains("/c is not in the bag; its topics: /a, /b"),
            "{err}"
        );
    }

    #[test]
    fn remaps_need_two_full_names() {
        assert_eq!(
            parse_remap("/ns/tf:=/tf").unwrap(),
            ("/ns/tf".to_string(), "/tf".to_string())
        );
        for bad in ["/ns/tf", "tf:=/tf", "/ns/tf:=tf", "/ns/tf:=/"] {
            let err = parse_remap(bad).unwrap_err();
            assert!(err.contains(&format!("remap `{bad}` is invalid")), "{err}");
        }
    }

    #[test]
    fn the_recorded_qos_is_offered_again() {
        let latched = OfferedQos::discovered(true, true);
        let volatile = OfferedQos::discovered(true, false);
        let qos = replay_qos(std::slice::from_ref(&latched));
        assert_eq!(qos.durability(), Some(policy::Durability::TransientLocal));
        assert!(matches!(
            qos.reliability(),
            Some(policy::Reliability::Reliable { .. })
        ));
        // Mixed publishers: what every one of them offered.
        let qos = replay_qos(&[latched, volatile.clone()]);
        assert_eq!(qos.durability(), Some(policy::Durability::Volatile));
        let qos = replay_qos(&[OfferedQos::discovered(false, false), volatile]);
        assert_eq!(qos.reliability(), Some(policy::Reliability::BestEffort));
        let mut deep = OfferedQos::discovered(true, false);
        deep.history = "keep_last".into();
        deep.depth = 50;
        assert_eq!(
            replay_qos(&[deep]).history(),
            Some(policy::History::KeepLast { depth: 50 })
        );
    }

    #[test]
    fn messages_are_due_at_their_recorded_offset_over_the_rate() {
        assert_eq!(
            due_after(3_000_000_000, 1_000_000_000, 2.0),
            Duration::from_secs(1)
        );
        assert_eq!(
            due_after(1_000, 2_000, 1.0),
            Duration::ZERO,
            "out of order: at once"
        );
        assert_eq!(
            dds_type_name("composuite_msgs/msg/Observation"),
            "composuite_msgs::msg::dds_::Observation_"
        );
    }
}
