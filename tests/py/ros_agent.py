"""A small ROS 2 agent over raw DDS (the `cyclonedds` Python package), for the integration tests.

It talks to our nodes the way an rclpy agent on rmw_cyclonedds would, without a ROS install:

* message types are built at import time from the interface files of this repository
  (msgs/msg, msgs/srv and the standard definitions in msgs/standard), parsed with the `rosbags`
  parser msgcheck.py already relies on, and turned into cyclonedds `IdlStruct` classes named as
  ROS names them on the wire (`pkg::msg::dds_::Name_`). They stay "final" so cyclonedds encodes
  them as XCDR1, the only representation rmw_cyclonedds and ros2-client speak;
* ROS names map to DDS topics as the RMWs do (`rt/...`, `rq/...Request`, `rr/...Reply`);
* QoS profiles carry the ROS names the design uses (`state`, `latched`, `clock`, `services`);
* `Agent` bundles one DomainParticipant with publishers, ordered sample buffers, a
  deadline-based `wait_for`, service clients in the rmw_cyclonedds or Fast DDS request format,
  and a view of every remote endpoint from DDS discovery.

Only run it inside scripts/netns-isolate (or netns-run): creating an Agent starts DDS discovery.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import itertools
import os
import re
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription
from cyclonedds.core import InstanceState, Policy, Qos, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlMeta, IdlStruct
from cyclonedds.idl import types as idl
from cyclonedds.internal import InvalidSample
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from rosbags.interfaces import Nodetype
from rosbags.typesys import get_types_from_msg

import msgcheck

# ---- interface definitions ------------------------------------------------------------------

# ROS 2 primitive -> cyclonedds annotation. `byte` and `char` are octets in ROS 2; mapping both to
# uint8 keeps their Python values plain ints (cyclonedds would decode `byte` arrays as `bytes`).
PRIMITIVES: dict[str, Any] = {
    "bool": bool,
    "byte": idl.uint8, "char": idl.uint8,
    "int8": idl.int8, "uint8": idl.uint8,
    "int16": idl.int16, "uint16": idl.uint16,
    "int32": idl.int32, "uint32": idl.uint32,
    "int64": idl.int64, "uint64": idl.uint64,
    "float32": idl.float32, "float64": idl.float64,
}
PRIMITIVE_DEFAULTS = {"bool": False, "float32": 0.0, "float64": 0.0, "string": ""}

# What rosidl adds to a struct without fields, so that it has a size (an empty service request).
EMPTY_STRUCT_MEMBER = "structure_needs_at_least_one_member"

# The two members rmw_cyclonedds puts in front of every request and reply (its request/reply
# header, read in rmw_cyclonedds' Jazzy serdata code: the client's GUID and a sequence number).
CYCLONE_HEADER = (("client_guid", idl.uint64), ("seq", idl.int64))


_DEFAULT_LINE = re.compile(r"^\s*([A-Za-z]\w*(?:\[[^\]]*\])?)\s+([a-z]\w*)\s+(\S.*?)\s*$")


def field_defaults(text: str) -> dict[str, Any]:
    """Default values written in a definition (`float64 w 1` in Quaternion.msg), which the rosbags
    parser drops. Only numeric and bool defaults, and arrays of them; constants (`=`) are not
    defaults."""
    defaults = {}
    for line in text.splitlines():
        line = line.split("#", 1)[0]
        match = _DEFAULT_LINE.match(line)
        if not match or "=" in line:
            continue
        base, field, literal = match[1].split("[")[0].split("/")[-1], match[2], match[3]
        if base == "bool":
            literal = {"true": "True", "false": "False"}.get(literal.lower(), literal)
        elif base not in PRIMITIVES:
            continue
        value = ast.literal_eval(literal)
        cast = float if base.startswith("float") else bool if base == "bool" else int
        defaults[field] = [cast(v) for v in value] if isinstance(value, (list, tuple)) else cast(value)
    return defaults


def interface_texts() -> dict[str, str]:
    """The definition text of every type by ROS name: the standard messages in msgs/standard and
    msgs/ros2_control, composuite_msgs' msg/, and each half of its srv/ files as
    `pkg/srv/Name_Request`/`_Response`."""
    texts = {name: path.read_text() for name, path in msgcheck.other_message_files().items()}
    msgs, srvs = msgcheck.own_interface_files()
    texts.update(msgs)
    for name, text in srvs.items():
        halves = re.split(r"^---[ \t]*$", text, flags=re.MULTILINE)
        if len(halves) != 2:
            raise ValueError(f"{name}: a .srv file needs exactly one '---' line")
        texts[f"{name}_Request"], texts[f"{name}_Response"] = halves
    return texts


def interface_definitions(texts: dict[str, str]) -> dict[str, tuple[list, list]]:
    """Field definitions by ROS type name in the rosbags form
    `(constants, [(field, (Nodetype, detail)), ...])`."""
    definitions: dict[str, tuple[list, list]] = {}
    for name, text in texts.items():
        # Parse under a msg-style name so that relative type names in a service half resolve
        # against its package, then file it under the service name.
        (_, definition), = get_types_from_msg(text, name.replace("/srv/", "/msg/")).items()
        definitions[name] = definition
    return definitions


def dds_type_name(ros_type: str) -> str:
    """`sensor_msgs/msg/JointState` -> `sensor_msgs::msg::dds_::JointState_` (also for
    `pkg/srv/Name_Request`)."""
    package, kind, name = ros_type.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def ros_type_name(dds_type: str) -> str:
    """The inverse of `dds_type_name`; returns the input unchanged if it is not a ROS type."""
    match = re.fullmatch(r"(\w+)::(msg|srv|action)::dds_::(\w+)_", dds_type)
    return f"{match[1]}/{match[2]}/{match[3]}" if match else dds_type


def _normalise_type_name(name: str) -> str:
    """Accept `pkg/msg/Name` and the ROS 1 style short form `pkg/Name`."""
    parts = name.split("/")
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    return name


class TypeRegistry(Mapping):
    """The cyclonedds classes of every interface type, by ROS name:
    `registry["sensor_msgs/msg/JointState"]`, `registry["composuite_msgs/srv/Reset_Request"]`.
    Classes are dataclasses whose fields default to zero values, so `cls()` is a valid message.
    `cyclone_service(...)` gives the request/reply classes with the rmw_cyclonedds header."""

    def __init__(self, texts: dict[str, str]):
        self.definitions = interface_definitions(texts)
        self.defaults = {name: field_defaults(text) for name, text in texts.items()}
        self._classes: dict[str, type] = {}
        self._wire: dict[tuple[str, str], type] = {}
        for name in self.definitions:
            self._build(name)

    # Mapping interface
    def __getitem__(self, name: str) -> type:
        name = _normalise_type_name(name)
        if name not in self._classes:
            raise KeyError(f"unknown ROS type {name!r}; known: {', '.join(sorted(self._classes))}")
        return self._classes[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._classes)

    def __len__(self) -> int:
        return len(self._classes)

    def fields(self, name: str) -> list[tuple[str, tuple]]:
        """The layout fields of a type (constants left out), with an empty struct's filler."""
        fields = list(self.definitions[_normalise_type_name(name)][1])
        return fields or [(EMPTY_STRUCT_MEMBER, (Nodetype.BASE, ("uint8", 0)))]

    def constants(self, name: str) -> dict[str, Any]:
        return {c: value for c, _, value in self.definitions[_normalise_type_name(name)][0]}

    def _build(self, name: str) -> type:
        if name in self._classes:
            return self._classes[name]
        if name not in self.definitions:
            raise KeyError(f"type {name!r} is used but not defined in msgs/")
        annotations, defaults = {}, {}
        for field, desc in self.fields(name):
            annotations[field], defaults[field] = self._annotation(desc)
            if field in self.defaults[name]:
                written = self.defaults[name][field]
                defaults[field] = lambda written=written: written.copy() if isinstance(written, list) else written
        cls = _make_struct(name.split("/")[-1], dds_type_name(name), annotations, defaults)
        cls.ros_name = name
        self._classes[name] = cls
        return cls

    def _annotation(self, desc) -> tuple[Any, Callable[[], Any]]:
        """The cyclonedds annotation of one field and a factory of its default value."""
        kind, detail = desc
        if kind == Nodetype.BASE:
            base, bound = detail
            if base == "string":
                return (idl.bounded_str[bound] if bound else str), str
            if base not in PRIMITIVES:
                raise ValueError(f"unsupported primitive type {base!r}")
            default = PRIMITIVE_DEFAULTS.get(base, 0)
            return PRIMITIVES[base], (lambda: default)
        if kind == Nodetype.NAME:
            cls = self._build(detail)
            return cls, cls
        (sub_kind, sub_detail), count = detail
        inner, inner_default = self._annotation((sub_kind, sub_detail))
        if kind == Nodetype.ARRAY:
            return idl.array[inner, count], (lambda: [inner_default() for _ in range(count)])
        # SEQUENCE: count is the bound, 0 = unbounded
        return (idl.sequence[inner, count] if count else idl.sequence[inner]), list

    def cyclone_service(self, srv_type: str) -> tuple[type, type]:
        """Request and reply classes of `pkg/srv/Name` in rmw_cyclonedds' format: the ROS type
        names, with `client_guid: uint64` and `seq: int64` in front of the ROS fields."""
        pair = []
        for half in ("Request", "Response"):
            name = f"{srv_type}_{half}"
            if (srv_type, half) not in self._wire:
                plain = self[name]
                annotations = dict(CYCLONE_HEADER)
                defaults: dict[str, Callable[[], Any]] = {"client_guid": int, "seq": int}
                for field in dataclasses.fields(plain):
                    if field.name in annotations:
                        raise ValueError(f"{name}: field {field.name!r} clashes with the request header")
                    annotations[field.name] = plain.__annotations__[field.name]
                    defaults[field.name] = field.default_factory
                cls = _make_struct(f"{name.split('/')[-1]}Wire", dds_type_name(name), annotations, defaults)
                cls.ros_name = name
                self._wire[(srv_type, half)] = cls
            pair.append(self._wire[(srv_type, half)])
        return pair[0], pair[1]

    def build(self, ros_type: str | type, value: Any = None, **fields: Any) -> Any:
        """A message of `ros_type` from a dict tree (missing fields get zero values), keyword
        fields, or an existing message (returned as is). Unknown field names are an error."""
        cls = self[ros_type] if isinstance(ros_type, str) else ros_type
        if value is None:
            value = {}
        if isinstance(value, cls):
            if fields:
                return dataclasses.replace(value, **{k: self._value(cls, k, v) for k, v in fields.items()})
            return value
        if dataclasses.is_dataclass(value):
            value = to_dict(value)
        if not isinstance(value, Mapping):
            raise TypeError(f"{cls.ros_name}: expected a dict or {cls.__name__}, got {type(value).__name__}")
        value = {**value, **fields}
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(value) - known)
        if unknown:
            raise ValueError(f"{cls.ros_name} has no field(s) {unknown}; fields are {sorted(known)}")
        return cls(**{k: self._value(cls, k, v) for k, v in value.items()})

    def _value(self, cls: type, field: str, value: Any) -> Any:
        """Convert one field's value: nested dicts to messages, numpy arrays to lists."""
        annotation = cls.__annotations__[field]
        if hasattr(value, "tolist"):  # numpy arrays and scalars
            value = value.tolist()
        if isinstance(annotation, IdlMeta):
            return self.build(annotation, value)
        # arrays and sequences are Annotated[Sequence[T], array(T, n) | sequence(T, bound)]
        shape = getattr(annotation, "__metadata__", (None,))[0]
        if isinstance(shape, idl.array) and len(value) != shape.length:
            raise ValueError(f"{cls.ros_name}.{field} is a fixed array of {shape.length}, got {len(value)} values")
        if isinstance(shape, (idl.array, idl.sequence)):
            if isinstance(shape.subtype, IdlMeta):
                return [self.build(shape.subtype, v) for v in value]
            return list(value)
        return value


def _make_struct(class_name: str, typename: str, annotations: dict, defaults: dict) -> type:
    """A final (XCDR1: no extensibility annotation, no optional members) cyclonedds struct whose
    fields default to fresh values from `defaults` (factories)."""
    namespace = IdlMeta.__prepare__(class_name, (IdlStruct,), typename=typename)
    namespace["__annotations__"].update(annotations)
    for field, factory in defaults.items():
        namespace[field] = dataclasses.field(default_factory=factory)
    return dataclasses.dataclass(IdlMeta(class_name, (IdlStruct,), namespace))


def to_dict(message: Any) -> Any:
    """A plain dict/list tree of a message (drops cyclonedds' `sample_info` attribute)."""
    if dataclasses.is_dataclass(message) and not isinstance(message, type):
        return {f.name: to_dict(getattr(message, f.name)) for f in dataclasses.fields(message)}
    if isinstance(message, (list, tuple)):
        return [to_dict(v) for v in message]
    if isinstance(message, (bytes, bytearray)):
        return list(message)
    return message


@functools.lru_cache(maxsize=None)
def load_types() -> TypeRegistry:
    """The registry of this repository's interface types, built once per process so that every
    Agent (and the test code) uses the very same classes."""
    return TypeRegistry(interface_texts())


# ---- names -------------------------------------------------------------------------------------

_NAME_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def normalise_namespace(namespace: str | None) -> str:
    """`None`, `""`, `/` -> `/`; `env_00` or `/env_00/` -> `/env_00`."""
    namespace = (namespace or "/").strip()
    if not namespace.startswith("/"):
        namespace = "/" + namespace
    namespace = namespace.rstrip("/") or "/"
    _check_tokens(namespace, namespace)
    return namespace


def fully_qualified(name: str, namespace: str | None = "/") -> str:
    """The fully qualified ROS name: absolute names stay, relative ones get the namespace."""
    if not name or name.endswith("/"):
        raise ValueError(f"invalid ROS name {name!r}")
    if name.startswith("~"):
        raise ValueError(f"{name!r}: private names need a node; this agent has none")
    if name.startswith("/"):
        full = name
    else:
        namespace = normalise_namespace(namespace)
        full = f"{namespace.rstrip('/')}/{name}"
    _check_tokens(full, name)
    return full


def _check_tokens(full: str, shown: str) -> None:
    tokens = full.split("/")[1:]
    if full != "/" and not all(_NAME_TOKEN.fullmatch(t) for t in tokens):
        raise ValueError(f"invalid ROS name {shown!r}: tokens are letters, digits and '_', not starting with a digit")


def topic_name(name: str, namespace: str | None = "/") -> str:
    """DDS topic of a ROS topic: `rt` + fully qualified name."""
    return "rt" + fully_qualified(name, namespace)


def service_topic_names(name: str, namespace: str | None = "/") -> tuple[str, str]:
    """DDS request and reply topics of a ROS service."""
    full = fully_qualified(name, namespace)
    return f"rq{full}Request", f"rr{full}Reply"


def ros_name_of_topic(dds_topic: str) -> tuple[str, str]:
    """(`topic`|`service_request`|`service_reply`|`dds`, ROS name) of a DDS topic name."""
    if dds_topic.startswith("rt/"):
        return "topic", dds_topic[2:]
    if dds_topic.startswith("rq/") and dds_topic.endswith("Request"):
        return "service_request", dds_topic[2:-len("Request")]
    if dds_topic.startswith("rr/") and dds_topic.endswith("Reply"):
        return "service_reply", dds_topic[2:-len("Reply")]
    return "dds", dds_topic


# ---- QoS ---------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class QosProfile:
    """The three QoS settings ROS profiles differ in (the rest stay at the DDS defaults)."""

    reliability: str  # "reliable" | "best_effort"
    durability: str  # "volatile" | "transient_local"
    depth: int  # keep last N

    def to_dds(self, user_data: bytes | None = None, keep_all: bool = False) -> Qos:
        # 100 ms is the DDS default blocking time of a reliable writer with a full history.
        reliability = (Policy.Reliability.Reliable(duration(milliseconds=100)) if self.reliability == "reliable"
                       else Policy.Reliability.BestEffort)
        durability = {"volatile": Policy.Durability.Volatile,
                      "transient_local": Policy.Durability.TransientLocal}[self.durability]
        history = Policy.History.KeepAll if keep_all else Policy.History.KeepLast(self.depth)
        policies = [reliability, durability, history]
        if user_data:
            policies.append(Policy.Userdata(user_data))
        return Qos(*policies)


QOS_PROFILES = {
    "state": QosProfile("reliable", "volatile", 10),
    "latched": QosProfile("reliable", "transient_local", 1),
    "clock": QosProfile("best_effort", "volatile", 1),
    "services": QosProfile("reliable", "volatile", 10),
}


def qos_profile(qos: str | QosProfile) -> QosProfile:
    if isinstance(qos, QosProfile):
        return qos
    if qos not in QOS_PROFILES:
        raise ValueError(f"unknown QoS profile {qos!r}; known: {', '.join(QOS_PROFILES)}")
    return QOS_PROFILES[qos]


def describe_qos(qos: Qos | None) -> dict[str, Any]:
    """reliability / durability / history kind and depth of a cyclonedds Qos, as plain values
    (None for a policy the Qos does not hold; discovered endpoints hold them all, Cyclone fills
    in the DDS default for any a peer did not announce)."""
    qos = qos or Qos()
    reliability = qos[Policy.Reliability]
    durability = qos[Policy.Durability]
    history = qos[Policy.History]
    durability_names = {Policy.Durability.Volatile: "volatile", Policy.Durability.TransientLocal: "transient_local",
                        Policy.Durability.Transient: "transient", Policy.Durability.Persistent: "persistent"}
    return {
        "reliability": None if reliability is None else (
            "best_effort" if reliability == Policy.Reliability.BestEffort else "reliable"),
        "durability": None if durability is None else durability_names[durability],
        "history": None if history is None else ("keep_all" if history == Policy.History.KeepAll else "keep_last"),
        "depth": getattr(history, "depth", None),
    }


# ---- the agent ---------------------------------------------------------------------------------


def _domain_id(domain_id: int | None) -> int:
    if domain_id is not None:
        return domain_id
    text = os.environ.get("ROS_DOMAIN_ID", "").strip()
    return int(text) if text else 0


class Publisher:
    """A DDS writer on `rt/<name>`; `publish` takes a message or a dict tree."""

    def __init__(self, agent: Agent, name: str, ros_type: str, qos: QosProfile):
        self.agent, self.name, self.ros_type, self.qos = agent, name, ros_type, qos
        self.dds_topic = topic_name(name, agent.namespace)
        self.cls = agent.types[ros_type]
        topic = agent._topic(self.dds_topic, self.cls)
        self.writer = DataWriter(agent.participant, topic, qos=qos.to_dds())

    def publish(self, message: Any = None, **fields: Any) -> Any:
        message = self.agent.types.build(self.cls, message, **fields)
        self.writer.write(message)
        return message

    def matched(self) -> int:
        """How many readers currently match this writer."""
        return matched_readers(self.writer)

    def wait_for_subscribers(self, count: int = 1, timeout: float = 10.0) -> None:
        _wait_until(lambda: self.matched() >= count, timeout, f"{count} subscriber(s) of {self.dds_topic}")


class Subscription:
    """A DDS reader on `rt/<name>` whose samples are kept in arrival order: the agent's collector
    thread takes them out of the reader as they come. With `keep_all` (the default) the reader's
    own history is KEEP_ALL rather than the profile's depth, so a burst larger than the depth
    that arrives before the collector wakes up is not lost either. History is not part of QoS
    matching; reliability and durability still come from the profile."""

    def __init__(self, agent: Agent, name: str, ros_type: str, qos: QosProfile, keep_all: bool = True):
        self.agent, self.name, self.ros_type, self.qos = agent, name, ros_type, qos
        self.dds_topic = topic_name(name, agent.namespace)
        self.cls = agent.types[ros_type]
        topic = agent._topic(self.dds_topic, self.cls)
        self.reader = DataReader(agent.participant, topic, qos=qos.to_dds(keep_all=keep_all))
        self.condition = ReadCondition(self.reader, SampleState.NotRead | ViewState.Any | InstanceState.Any)
        self._samples: list[Any] = []
        self.errors: list[str] = []  # what the collector could not take (undecodable samples)
        self._changed = threading.Condition()

    def _drain(self) -> None:
        while True:
            batch = self.reader.take(N=256)
            if not batch:
                return
            valid = _valid(batch)
            if valid:
                with self._changed:
                    self._samples.extend(valid)
                    self._changed.notify_all()

    def _failed(self, error: Exception) -> None:
        # Keep the collector alive and say why in the next timeout instead.
        with self._changed:
            self.errors.append(f"{type(error).__name__}: {error}")
            self._changed.notify_all()

    @property
    def samples(self) -> list[Any]:
        """A copy of every sample received so far, oldest first."""
        with self._changed:
            return list(self._samples)

    def clear(self) -> None:
        with self._changed:
            self._samples.clear()

    def matched(self) -> int:
        """How many writers currently match this reader."""
        return matched_writers(self.reader)

    def wait_for_publishers(self, count: int = 1, timeout: float = 10.0) -> None:
        _wait_until(lambda: self.matched() >= count, timeout, f"{count} publisher(s) of {self.dds_topic}")

    def wait_for(self, predicate: Callable[[Any], bool] | Mapping[str, Any] | None = None,
                 timeout: float = 5.0, start: int = 0) -> Any:
        """The first received sample (from index `start`) for which `predicate` is true, waiting
        until a wall-clock deadline. A dict predicate compares dotted field paths:
        `{"header.stamp.sec": 3, "step": 3}`."""
        match = _as_predicate(predicate)
        deadline = time.monotonic() + timeout
        checked = start
        with self._changed:
            while True:
                for sample in self._samples[checked:]:
                    if match(sample):
                        return sample
                checked = max(checked, len(self._samples))
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise TimeoutError(
                        f"no sample on {self.dds_topic} matched {_describe(predicate)} within {timeout} s "
                        f"({len(self._samples)} received, {self.matched()} matched writer(s)"
                        + (f"; errors taking samples: {self.errors[-3:]}" if self.errors else "") + ")")
                self._changed.wait(remaining)


def _valid(samples: list) -> list:
    """Data samples only: a writer going away delivers data-less dispose/unregister samples."""
    return [s for s in samples if not isinstance(s, InvalidSample)]


def _as_predicate(predicate) -> Callable[[Any], bool]:
    if predicate is None:
        return lambda sample: True
    if callable(predicate):
        return predicate
    wanted = dict(predicate)

    def match(sample: Any) -> bool:
        for path, expected in wanted.items():
            value = sample
            for part in path.split("."):
                value = getattr(value, part)
            if dataclasses.is_dataclass(value) and isinstance(expected, Mapping):
                value = to_dict(value)
            if value != expected:
                return False
        return True

    return match


def _describe(predicate) -> str:
    if predicate is None:
        return "anything"
    if isinstance(predicate, Mapping):
        return repr(dict(predicate))
    return getattr(predicate, "__name__", repr(predicate))


def matched_readers(writer) -> int:
    """How many readers match `writer`, from its matched status. Not the binding's
    `get_matched_subscriptions()`: it sizes its list with one call and indexes it with the count a
    second call returns, so a reader matching in between raises IndexError (seen in CI)."""
    return writer.get_publication_matched_status().current_count


def matched_writers(reader) -> int:
    """How many writers match `reader` (see `matched_readers` for why not the list getter)."""
    return reader.get_subscription_matched_status().current_count


def _wait_until(condition: Callable[[], bool], timeout: float, what: str, poll: float = 0.01) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() >= deadline:
            raise TimeoutError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(poll)


@dataclasses.dataclass(frozen=True)
class Endpoint:
    """One endpoint seen in DDS discovery."""

    kind: str  # "publication" | "subscription"
    topic_name: str  # DDS name, e.g. rt/env_00/joint_states
    type_name: str  # DDS name, e.g. sensor_msgs::msg::dds_::JointState_
    reliability: str | None
    durability: str | None
    history: str | None
    depth: int | None
    participant: str  # participant GUID
    user_data: bytes | None

    @property
    def ros_type(self) -> str:
        return ros_type_name(self.type_name)

    @property
    def ros_name(self) -> str:
        return ros_name_of_topic(self.topic_name)[1]

    @property
    def ros_kind(self) -> str:
        return ros_name_of_topic(self.topic_name)[0]


# rmw_cyclonedds takes one process-wide counter for the `seq` of every client; so do we.
_SEQUENCE = itertools.count(1)
_SEQUENCE_LOCK = threading.Lock()


def _next_seq() -> int:
    with _SEQUENCE_LOCK:
        return next(_SEQUENCE)


class ServiceUnavailable(TimeoutError):
    pass


class ServiceClient:
    """A ROS service client over raw DDS.

    format="cyclone": the rmw_cyclonedds layout, a {client_guid, seq} header before the request
    fields, echoed in the reply; replies of other clients (other guid) and stale or foreign
    replies (other seq) are skipped, so calls correlate exactly.
    format="fastdds": no header (a Fast DDS server reads the identity from RTPS metadata this
    library cannot see), so at most one request is outstanding and the next reply is its answer;
    give each client its own service (one per namespace) to keep others' replies off the topic.

    Every call waits first until both endpoints match a server (an unmatched first request or
    reply is lost), then waits for the reply until a deadline, and retries once."""

    def __init__(self, agent: Agent, name: str, srv_type: str, format: str = "cyclone",
                 qos: str | QosProfile = "services"):
        if format not in ("cyclone", "fastdds"):
            raise ValueError(f"unknown service format {format!r}: 'cyclone' or 'fastdds'")
        self.agent, self.name, self.srv_type, self.format = agent, name, srv_type, format
        self.request_topic, self.reply_topic = service_topic_names(name, agent.namespace)
        self.request_cls = agent.types[f"{srv_type}_Request"]
        self.response_cls = agent.types[f"{srv_type}_Response"]
        if format == "cyclone":
            self.request_wire, self.reply_wire = agent.types.cyclone_service(srv_type)
        else:
            self.request_wire, self.reply_wire = self.request_cls, self.response_cls
        profile = qos_profile(qos)
        # rmw_cyclonedds tags both endpoints of a client with the same `clientid`, which lets its
        # server wait until the reply reader matched before answering.
        user_data = f"clientid={agent._next_endpoint_id()};".encode() if format == "cyclone" else None
        self.writer = DataWriter(agent.participant, agent._topic(self.request_topic, self.request_wire),
                                 qos=profile.to_dds(user_data))
        self.reader = DataReader(agent.participant, agent._topic(self.reply_topic, self.reply_wire),
                                 qos=profile.to_dds(user_data))
        self.waitset = WaitSet(agent.participant)
        self.waitset.attach(ReadCondition(self.reader, SampleState.Any | ViewState.Any | InstanceState.Any))
        # rmw_cyclonedds uses the request writer's instance handle as the client's id. cyclonedds
        # hands handles to Python as signed 64-bit ints; the header field is a uint64.
        self.client_guid = self.writer.instance_handle & 0xFFFF_FFFF_FFFF_FFFF
        self.ignored_replies = 0
        self._lock = threading.Lock()
        self._ready = False

    def service_is_ready(self) -> bool:
        return matched_readers(self.writer) > 0 and matched_writers(self.reader) > 0

    def wait_for_service(self, timeout: float = 10.0) -> None:
        try:
            _wait_until(self.service_is_ready, timeout, f"service {self.request_topic} / {self.reply_topic}")
        except TimeoutError as error:
            raise ServiceUnavailable(str(error)) from None
        self._ready = True

    def call(self, request: Any = None, timeout: float = 5.0, retries: int = 1, **fields: Any) -> Any:
        """Send a request (message, dict tree or keyword fields) and return the response as the
        plain `<srv>_Response` message. `timeout` bounds the first wait for the server
        (ServiceUnavailable) and each attempt; raises TimeoutError when all 1 + `retries`
        attempts went unanswered."""
        plain = to_dict(self.agent.types.build(self.request_cls, request, **fields))
        with self._lock:
            if not self._ready:
                self.wait_for_service(timeout)
            for _attempt in range(1 + retries):
                reply = self._attempt(plain, timeout)
                if reply is not None:
                    return reply
        raise TimeoutError(f"no reply from {self.reply_topic} within {timeout} s, {1 + retries} attempt(s)")

    def _attempt(self, plain: dict, timeout: float) -> Any:
        deadline = time.monotonic() + timeout
        if self.format == "cyclone":
            seq = _next_seq()
            self.writer.write(self.request_wire(client_guid=self.client_guid, seq=seq, **plain))
        else:
            # Without correlation, anything already waiting is a late answer to an earlier
            # attempt: drop it so the next reply belongs to this request.
            self.ignored_replies += len(self._take_valid())
            self.writer.write(self.request_wire(**plain))
        while True:
            for reply in self._take_valid():
                if self.format == "fastdds":
                    return reply
                if reply.client_guid == self.client_guid and reply.seq == seq:
                    fields = to_dict(reply)
                    del fields["client_guid"], fields["seq"]
                    return self.response_cls(**{k: getattr(reply, k) for k in fields})
                self.ignored_replies += 1
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            self.waitset.wait(duration(seconds=min(remaining, 0.1)))

    def _take_valid(self) -> list[Any]:
        out = []
        while True:
            batch = self.reader.take(N=64)
            if not batch:
                return out
            out.extend(_valid(batch))


def reset_with_joint_states(reset: "ServiceClient", states: "Subscription", seed: int,
                            attempts: int = 5) -> tuple[Any, Any]:
    """Reset (`seed`) through `reset` until the step-0 `joint_states` of that episode arrives on
    `states`; (reply, joint_states). The sim publishes joint_states at a reset, and its writer may
    match this reader only after that sample went out (each side sees the match on its own)."""
    for _ in range(attempts):
        reply = reset.call({"seed": seed, "use_seed": True}, timeout=10)
        if not reply.success:
            raise RuntimeError(f"reset refused: {reply.message}")
        try:
            return reply, states.wait_for({"header.stamp": reply.observation.header.stamp}, timeout=2)
        except TimeoutError:
            continue
    raise TimeoutError(f"no joint_states after {attempts} resets")


def _stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def stamped(ns: int) -> dict:
    """A std_msgs/Header (as a dict) stamped `ns` of sim time: what a lockstep command carries
    (the stamp of the observation it answers)."""
    return {"stamp": {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}}


class LockstepClient:
    """The agent's side of the lockstep protocol on one Agent: `reset(seed)` through the service,
    then each `step(targets)` publishes joint_command (stamped with the observation it answers)
    and waits for that step's observation and reward. Steps are matched on (episode, step) and
    on a stamp later than the reset's, since a restarted task manager counts episodes from 1
    again and a stamp never repeats.

        client = LockstepClient(agent)
        client.reset(seed=3)
        observation = client.step([q + 0.01 for q in client.home])
    """

    ARM_JOINTS = 7

    def __init__(self, agent: "Agent", service_format: str = "cyclone"):
        self.agent = agent
        self.states = agent.subscribe("joint_states", "sensor_msgs/msg/JointState")
        self.observations = agent.subscribe("observation", "composuite_msgs/msg/Observation")
        self.rewards = agent.subscribe("reward", "composuite_msgs/msg/StagedReward")
        self.command = agent.publisher("joint_command", "sensor_msgs/msg/JointState")
        self.reset_client = agent.service_client("reset", "composuite_msgs/srv/Reset", service_format)
        self.episode = self.step_count = self.since = None
        self.names: list[str] = []
        self.home: list[float] = []

    def reset(self, seed: int) -> Any:
        """Start an episode with `seed`; the reply. Sets `names` and `home` (the arm's joints and
        their start positions, from the episode's first joint_states)."""
        reply, first = reset_with_joint_states(self.reset_client, self.states, seed=seed)
        self.started(reply, first)
        return reply

    def started(self, reply: Any, first: Any) -> None:
        """Take `reply` (a successful reset) and its episode's first joint_states as the start."""
        self.episode, self.step_count = reply.episode, 0
        self.since = _stamp_ns(reply.observation.header.stamp)
        self.answered = self.since  # the stamp the next command carries
        self.names = list(first.name[:self.ARM_JOINTS])
        self.home = list(first.position[:self.ARM_JOINTS])

    def this_episode(self, step: int) -> Callable[[Any], bool]:
        """A predicate: the message of `step` of the current episode."""
        episode, since = self.episode, self.since

        def match(message: Any) -> bool:
            return message.episode == episode and message.step == step and _stamp_ns(message.header.stamp) > since
        match.__name__ = f"episode {episode} step {step}"
        return match

    def step(self, targets: list[float], timeout: float = 5.0, reward: bool = True) -> Any:
        """One lockstep step to `targets` (absolute arm joint positions); its observation."""
        self.command.publish(name=self.names, position=[float(t) for t in targets],
                             header=stamped(self.answered))
        self.step_count += 1
        want = self.this_episode(self.step_count)
        observation = self.observations.wait_for(want, timeout=timeout)
        self.answered = _stamp_ns(observation.header.stamp)
        if reward:
            self.rewards.wait_for(want, timeout=timeout)
        return observation


class Agent:
    """One DDS participant acting as a ROS 2 agent in a namespace.

        with Agent(namespace="/env_00") as agent:
            agent.subscribe("observation", "composuite_msgs/msg/Observation")
            cmd = agent.publisher("joint_command", "sensor_msgs/msg/JointState")
            cmd.publish({"name": names, "position": targets})
            obs = agent.wait_for("observation", {"step": 1}, timeout=5)
    """

    def __init__(self, namespace: str = "/", domain_id: int | None = None, types: TypeRegistry | None = None):
        self.namespace = normalise_namespace(namespace)
        self.domain_id = _domain_id(domain_id)
        self.types = types or load_types()
        self.participant = DomainParticipant(self.domain_id)
        self._topics: dict[str, Topic] = {}
        self._publishers: dict[str, Publisher] = {}
        self._subscriptions: dict[str, Subscription] = {}
        self._clients: list[ServiceClient] = []
        self._endpoint_ids = itertools.count(1)
        self._lock = threading.Lock()
        # Builtin readers exist from the start so discovery data is there when asked for.
        self._discovery = {
            "publication": BuiltinDataReader(self.participant, BuiltinTopicDcpsPublication),
            "subscription": BuiltinDataReader(self.participant, BuiltinTopicDcpsSubscription),
        }
        self._waitset = WaitSet(self.participant)
        self._closed = False
        self._collector = threading.Thread(target=self._collect, name=f"ros_agent {self.namespace}", daemon=True)
        self._collector.start()

    # -- lifecycle

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._waitset.set_trigger(True)
        self._collector.join(timeout=5)
        # Deleting the participant deletes every reader and writer under it (peers see them go).
        self.participant.__del__()

    def __enter__(self) -> Agent:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _collect(self) -> None:
        while not self._closed:
            self._waitset.wait(duration(milliseconds=200))
            # The trigger (set by subscribe and close) stays up until cleared; clear it or spin.
            self._waitset.set_trigger(False)
            with self._lock:
                subscriptions = list(self._subscriptions.values())
            for subscription in subscriptions:
                if self._closed:
                    return
                try:
                    subscription._drain()
                except Exception as error:  # e.g. bytes that do not decode as the type
                    subscription._failed(error)

    # -- entities

    def _topic(self, dds_name: str, cls: type) -> Topic:
        key = f"{dds_name}\0{cls.__idl_typename__}\0{id(cls)}"
        with self._lock:
            if key not in self._topics:
                self._topics[key] = Topic(self.participant, dds_name, cls)
            return self._topics[key]

    def _next_endpoint_id(self) -> str:
        # participant GUID prefix (12 bytes) + a counter, dot-separated hex as rmw_cyclonedds writes it
        prefix = self.participant.guid.bytes[:12] + next(self._endpoint_ids).to_bytes(4, "big")
        return ".".join(f"{b:02x}" for b in prefix)

    def resolve(self, name: str) -> str:
        """Fully qualified ROS name of `name` in this agent's namespace."""
        return fully_qualified(name, self.namespace)

    def publisher(self, name: str, ros_type: str, qos: str | QosProfile = "state") -> Publisher:
        """A publisher of `ros_type` on ROS topic `name` (relative names get the namespace)."""
        profile = qos_profile(qos)
        key = self.resolve(name)
        with self._lock:
            existing = self._publishers.get(key)
        if existing:
            if (existing.ros_type, existing.qos) != (_normalise_type_name(ros_type), profile):
                raise ValueError(f"{key} already has a publisher of {existing.ros_type} with {existing.qos}")
            return existing
        publisher = Publisher(self, name, _normalise_type_name(ros_type), profile)
        with self._lock:
            self._publishers[key] = publisher
        return publisher

    def subscribe(self, name: str, ros_type: str, qos: str | QosProfile = "state",
                  keep_all: bool = True) -> Subscription:
        """Start keeping every sample of ROS topic `name`, in arrival order (see Subscription
        for `keep_all`)."""
        profile = qos_profile(qos)
        key = self.resolve(name)
        with self._lock:
            existing = self._subscriptions.get(key)
        if existing:
            if (existing.ros_type, existing.qos) != (_normalise_type_name(ros_type), profile):
                raise ValueError(f"{key} is already subscribed as {existing.ros_type} with {existing.qos}")
            return existing
        subscription = Subscription(self, name, _normalise_type_name(ros_type), profile, keep_all)
        with self._lock:
            self._subscriptions[key] = subscription
            self._waitset.attach(subscription.condition)
        # Wake the collector: samples (a latched one) may have arrived before the attach.
        self._waitset.set_trigger(True)
        return subscription

    def subscription(self, name: str) -> Subscription:
        key = self.resolve(name)
        with self._lock:
            if key not in self._subscriptions:
                raise KeyError(f"not subscribed to {key}; call subscribe() first")
            return self._subscriptions[key]

    def samples(self, name: str) -> list[Any]:
        """Every sample received on `name` so far, oldest first."""
        return self.subscription(name).samples

    def wait_for(self, name: str, predicate: Callable[[Any], bool] | Mapping[str, Any] | None = None,
                 timeout: float = 5.0, start: int = 0) -> Any:
        """The first sample on `name` matching `predicate` (a callable, or a dict of dotted field
        paths to values such as `{"step": 3}`), waiting up to `timeout` wall-clock seconds.
        Match on what identifies the sample you want (stamp, episode, step): this never means
        "the latest message"."""
        return self.subscription(name).wait_for(predicate, timeout, start)

    def service_client(self, name: str, srv_type: str, format: str = "cyclone",
                       qos: str | QosProfile = "services") -> ServiceClient:
        """A client of service `name` of type `pkg/srv/Name` in the given wire format."""
        client = ServiceClient(self, name, srv_type, format, qos)
        self._clients.append(client)
        return client

    # -- discovery

    def discovered_topics(self, include_own: bool = False) -> list[Endpoint]:
        """Every endpoint DDS discovery knows of, with its topic and type names and QoS; by default
        only those of other participants. Discovery is asynchronous: poll with
        `wait_for_endpoint` when something must have appeared.

        QoS policies a peer leaves out of its discovery data are reported with the DDS default
        values (Cyclone fills them in). History is one of them for some peers: RustDDS (under
        ros2-client) never announces it, so its endpoints show keep_last 1 whatever they use."""
        own = self.participant.guid
        endpoints = []
        for kind, reader in self._discovery.items():
            condition = ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Alive)
            for sample in reader.read(N=100_000, condition=condition):
                if not include_own and sample.participant_key == own:
                    continue
                # Cyclone lists its in-process builtin-topic readers too; they are not on the wire.
                if sample.type_name.startswith("org::eclipse::cyclonedds::"):
                    continue
                user_data = sample.qos[Policy.Userdata] if sample.qos is not None else None
                endpoints.append(Endpoint(
                    kind=kind, topic_name=sample.topic_name, type_name=sample.type_name,
                    participant=str(sample.participant_key),
                    user_data=user_data.data if user_data is not None else None,
                    **describe_qos(sample.qos),
                ))
        return sorted(endpoints, key=lambda e: (e.topic_name, e.kind, e.participant))

    def wait_for_endpoint(self, predicate: Callable[[Endpoint], bool], timeout: float = 10.0,
                          include_own: bool = False) -> Endpoint:
        """The first discovered endpoint matching `predicate`, polling until the deadline."""
        found: list[Endpoint] = []

        def seen() -> bool:
            found[:] = [e for e in self.discovered_topics(include_own) if predicate(e)]
            return bool(found)

        _wait_until(seen, timeout, f"a discovered endpoint matching {_describe(predicate)}", poll=0.05)
        return found[0]
