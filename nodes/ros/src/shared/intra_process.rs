//! Intra-process hand-off, as ROS 2's intra-process communication does it: inside one composed
//! process a message goes from its publisher to the subscriptions of the same topic in that
//! process directly (a clone through a channel), so they need not wait for the DDS round trip —
//! the participant's event loop, a loopback datagram, its reception and the wake-up of the
//! reader's thread. The same message still goes on the wire, for every reader outside the
//! process (agents, the recorder, `ros2 topic echo`).
//!
//! A subscription in the process also receives the wire copy of a message it already got in
//! the process (the participant's readers match its writers like any others): it drops every
//! wire sample whose writer hands its messages over here, so each message is taken once. The
//! hand-off saves the wait, not the wire's work: those copies are still sent, received and
//! decoded before they are dropped. Samples of other writers (another process's, a publisher
//! that is not handed over) come by the wire as before.
//!
//! Only volatile topics with a reliable publisher are handed over: a volatile subscription gets
//! what is published after it exists and nothing older, which a channel gives, and a reliable
//! publisher reaches every matching subscription. Latched topics (the scene, once per episode)
//! keep their history on the wire. A subscription's queue keeps its QoS depth, dropping the
//! oldest message when full, like a keep-last reader cache.

use std::any::Any;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex, RwLock};

use futures::StreamExt;
use futures::stream::FusedStream;
use ros2_client::dds::{Publisher as WirePublisher, Subscription as WireSubscription};
use ros2_client::qos::{Durability, History, Reliability};
use ros2_client::{
    Gid, Message, MessageInfo, QosProfile, ROSTime, ReadResult, SystemTime, WriteResult,
};

/// The topics handed over inside one process (one per composed process, shared by its nodes).
#[derive(Default)]
pub struct IntraProcess {
    /// Absolute topic name → its [`LocalTopic`] of the topic's message type.
    topics: Mutex<HashMap<String, Arc<dyn Any + Send + Sync>>>,
}

impl IntraProcess {
    /// No topics yet.
    pub fn new() -> IntraProcess {
        IntraProcess::default()
    }

    /// Topic `name` carrying `M`; `None` if the name is taken by another type (ROS does not
    /// allow that; those endpoints use the wire alone and DDS reports the mismatch).
    fn topic<M: Send + 'static>(&self, name: &str) -> Option<Arc<LocalTopic<M>>> {
        let mut topics = self.topics.lock().expect("no panic holds the topic table");
        let entry = topics
            .entry(name.to_string())
            .or_insert_with(|| Arc::new(LocalTopic::<M>::default()));
        Arc::clone(entry).downcast::<LocalTopic<M>>().ok()
    }
}

/// A message as a subscription receives it, with its metadata.
type Received<M> = (M, MessageInfo);

/// One topic's subscriptions in the process, and the writers that hand over to them.
struct LocalTopic<M> {
    subscriptions: Mutex<Vec<async_channel::Sender<Received<M>>>>,
    /// The writers whose messages the subscriptions get here, so drop when they come by the
    /// wire. Never shrinks: a writer's last wire samples may arrive after it is gone.
    writers: RwLock<HashSet<Gid>>,
}

impl<M> Default for LocalTopic<M> {
    fn default() -> Self {
        LocalTopic {
            subscriptions: Mutex::new(Vec::new()),
            writers: RwLock::new(HashSet::new()),
        }
    }
}

impl<M: Clone> LocalTopic<M> {
    /// Count `writer`'s messages as handed over here.
    fn add_writer(&self, writer: Gid) {
        self.writers
            .write()
            .expect("no panic holds the writer set")
            .insert(writer);
    }

    /// Whether `writer` hands its messages over here (so its wire samples are copies).
    fn hands_over(&self, writer: Gid) -> bool {
        self.writers
            .read()
            .expect("no panic holds the writer set")
            .contains(&writer)
    }

    /// A new subscription's queue: keeps the last `depth` messages (`None`: every message).
    fn subscribe(&self, depth: Option<usize>) -> async_channel::Receiver<Received<M>> {
        let (queue, receiver) = match depth {
            Some(depth) => async_channel::bounded(depth.max(1)),
            None => async_channel::unbounded(),
        };
        self.subscriptions
            .lock()
            .expect("no panic holds the subscription list")
            .push(queue);
        receiver
    }

    /// Give every subscription its copy of `message`, dropping a full queue's oldest message.
    fn hand_over(&self, message: &M, info: &MessageInfo) {
        let mut subscriptions = self
            .subscriptions
            .lock()
            .expect("no panic holds the subscription list");
        // A closed queue is a subscription that was dropped: forget it.
        subscriptions.retain(|queue| queue.force_send((message.clone(), info.clone())).is_ok());
    }
}

/// Whether endpoints of this QoS take part in the hand-off (see the module's documentation).
fn handed_over(qos: &QosProfile) -> bool {
    qos.durability == Durability::Volatile
        && matches!(qos.reliability, Reliability::Reliable { .. })
}

/// Topic `name` of `process` for an endpoint of `qos`: `None` outside a composed process or when
/// the QoS keeps the endpoint on the wire alone.
fn local_topic<M: Send + 'static>(
    process: Option<&IntraProcess>,
    name: &str,
    qos: &QosProfile,
) -> Option<Arc<LocalTopic<M>>> {
    process
        .filter(|_| handed_over(qos))
        .and_then(|p| p.topic::<M>(name))
}

/// A publisher: the wire's, and the hand-off to this process's subscriptions of the topic.
pub struct Publisher<M: Message> {
    wire: WirePublisher<M>,
    local: Option<Arc<LocalTopic<M>>>,
    sequence: AtomicI64,
}

impl<M: Message + Clone + Send + 'static> Publisher<M> {
    /// `wire` on topic `name`, handed over in `process` when given and `qos` allows.
    pub fn new(
        wire: WirePublisher<M>,
        name: &str,
        qos: &QosProfile,
        process: Option<&IntraProcess>,
    ) -> Publisher<M> {
        let local = local_topic::<M>(process, name, qos);
        if let Some(topic) = &local {
            topic.add_writer(wire.gid());
        }
        Publisher {
            wire,
            local,
            sequence: AtomicI64::new(0),
        }
    }

    /// Hand `message` to the subscriptions in this process, then publish it on the wire.
    /// Fails only when DDS does (it is shutting down).
    pub fn publish(&self, message: M) -> WriteResult<(), M> {
        if let Some(topic) = &self.local {
            let sequence = self.sequence.fetch_add(1, Ordering::Relaxed) + 1;
            let now = ROSTime::from(SystemTime::now());
            let info = MessageInfo::new(Some(now), Some(now), sequence, self.wire.gid(), None);
            topic.hand_over(&message, &info);
        }
        self.wire.publish(message)
    }

    /// The wire publisher's GID.
    pub fn gid(&self) -> Gid {
        self.wire.gid()
    }

    /// Wait until every reader on the wire has what was published, up to `max_wait` (true when
    /// all have): see `ros2_client`'s publisher.
    pub fn wait_for_acknowledgments(&self, max_wait: std::time::Duration) -> WriteResult<bool, ()> {
        self.wire.wait_for_acknowledgments(max_wait)
    }
}

/// A subscription: the messages handed over in this process, and the wire's from elsewhere.
pub struct Subscription<M> {
    wire: WireSubscription<M>,
    local: Option<LocalEnd<M>>,
}

/// A subscription's end of the hand-off: its queue, and its topic to tell the wire copies of
/// handed-over messages by their writer.
struct LocalEnd<M> {
    topic: Arc<LocalTopic<M>>,
    queue: async_channel::Receiver<Received<M>>,
}

impl<M: Message + Clone + Send + 'static> Subscription<M> {
    /// `wire` on topic `name`, receiving hand-overs in `process` when given and `qos` allows.
    pub fn new(
        wire: WireSubscription<M>,
        name: &str,
        qos: &QosProfile,
        process: Option<&IntraProcess>,
    ) -> Subscription<M> {
        let local = local_topic::<M>(process, name, qos).map(|topic| {
            let depth = match qos.history {
                History::KeepLast { depth } => Some(depth),
                History::KeepAll => None,
            };
            let queue = topic.subscribe(depth);
            LocalEnd { topic, queue }
        });
        Subscription { wire, local }
    }

    /// Every message as it comes, from the process or the wire, each once.
    pub fn async_stream(&self) -> impl FusedStream<Item = ReadResult<(M, MessageInfo)>> + '_ {
        let wire = self.wire.async_stream();
        match &self.local {
            Some(LocalEnd { topic, queue }) => {
                let from_elsewhere = wire.filter(move |sample| {
                    let handed_over =
                        matches!(sample, Ok((_, info)) if topic.hands_over(info.publisher_gid()));
                    std::future::ready(!handed_over)
                });
                futures::stream::select(queue.clone().map(Ok), from_elsewhere).left_stream()
            }
            None => wire.right_stream(),
        }
    }

    /// Whether this subscription receives hand-overs in its process.
    pub fn is_handed_over(&self) -> bool {
        self.local.is_some()
    }
}

#[cfg(test)]
mod test {
    use super::*;

    fn writer(n: u8) -> Gid {
        Gid::from([n; 16])
    }

    fn info(sequence: i64) -> MessageInfo {
        MessageInfo::new(None, None, sequence, writer(1), None)
    }

    fn drain(receiver: &async_channel::Receiver<(u32, MessageInfo)>) -> Vec<u32> {
        std::iter::from_fn(|| receiver.try_recv().ok().map(|(m, _)| m)).collect()
    }

    #[test]
    fn every_subscription_gets_each_message_once() {
        let topic = LocalTopic::<u32>::default();
        let first = topic.subscribe(Some(10));
        let second = topic.subscribe(None);
        for m in 0..5 {
            topic.hand_over(&m, &info(m.into()));
        }
        assert_eq!(drain(&first), [0, 1, 2, 3, 4]);
        assert_eq!(drain(&second), [0, 1, 2, 3, 4]);
        assert_eq!(drain(&first), [] as [u32; 0], "nothing twice");
    }

    #[test]
    fn a_full_queue_keeps_the_last_depth_messages() {
        let topic = LocalTopic::<u32>::default();
        let keep_three = topic.subscribe(Some(3));
        for m in 0..7 {
            topic.hand_over(&m, &info(m.into()));
        }
        assert_eq!(drain(&keep_three), [4, 5, 6]);
    }

    #[test]
    fn a_dropped_subscription_is_forgotten() {
        let topic = LocalTopic::<u32>::default();
        let kept = topic.subscribe(Some(10));
        drop(topic.subscribe(Some(10)));
        topic.hand_over(&1, &info(1));
        assert_eq!(topic.subscriptions.lock().unwrap().len(), 1);
        assert_eq!(drain(&kept), [1]);
    }

    // The wire copies of a writer that hands over are recognised (and dropped by the
    // subscription's stream); any other writer's samples are not.
    #[test]
    fn only_handing_writers_samples_are_copies() {
        let topic = LocalTopic::<u32>::default();
        topic.add_writer(writer(1));
        assert!(topic.hands_over(writer(1)));
        assert!(!topic.hands_over(writer(2)));
    }

    #[test]
    fn a_topic_is_one_type_and_shared_by_name() {
        let process = IntraProcess::new();
        let a = process.topic::<u32>("/env_00/world_state").unwrap();
        let b = process.topic::<u32>("/env_00/world_state").unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert!(process.topic::<String>("/env_00/world_state").is_none());
        let other = process.topic::<u32>("/env_01/world_state").unwrap();
        assert!(!Arc::ptr_eq(&a, &other), "environments do not share topics");
    }

    #[test]
    fn only_volatile_reliable_topics_are_handed_over() {
        use crate::shared::qos;
        assert!(handed_over(&qos::state()));
        assert!(
            !handed_over(&qos::latched()),
            "a late subscription needs the history"
        );
        assert!(!handed_over(&qos::clock()), "best effort");
    }
}
