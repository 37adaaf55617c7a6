// A ROS 2 agent for the suite that is not ours: stock Fast DDS (Debian's 2.9, built with
// OpenSSL and the DDS-Security builtin plugins) with no ROS layer in between. It joins the way
// rmw_fastrtps joins a participant from an SROS2 enclave (the same plugin names and file://
// properties) and speaks the ROS 2 wire conventions by hand — `rt/` topics, `rq/`/`rr/`
// services in rmw_fastrtps' format, `pkg::msg::dds_::Type_` names, CDR little endian — so
// whatever it gets from a secured suite went through a DDS-Security implementation nobody here
// wrote. It plays one lockstep episode and prints every step as a JSON line (doubles as the
// hex of their little-endian bytes, so the test compares bits, not decimal text).
//
//   fastdds_secure_peer --domain D --namespace /ns --seed S --steps N [--enclave DIR]
//                       [--expect-no-suite SECONDS] [--second-observation-reader] [--verbose]
//
// Without --enclave the participant has no security at all. --expect-no-suite: succeed (exit
// 0) only if nothing of the suite matches within SECONDS — what a peer the secured suite must
// refuse should see. --second-observation-reader: a second reader of `observation` in the same
// participant, its count of samples reported at the end. Exit 1 on any failure, with the
// reason on stderr.

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/rtps/common/WriteParams.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <regex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::SerializedPayload_t;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::WriteParams;

namespace {

// ---- CDR (XCDR1, little endian) -------------------------------------------------------------
// Alignment counts from the first byte after the 4-byte encapsulation header, as CDR wants.

struct CdrOut {
  std::vector<uint8_t> bytes;
  void align(size_t n) { while (bytes.size() % n) bytes.push_back(0); }
  template <typename T> void raw(T v) {
    align(sizeof(T));
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // x86-64 is little endian, as the encapsulation says
    bytes.insert(bytes.end(), b, b + sizeof(T));
  }
  void u32(uint32_t v) { raw(v); }
  void i32(int32_t v) { raw(v); }
  void u64(uint64_t v) { raw(v); }
  void f64(double v) { raw(v); }
  void boolean(bool v) { bytes.push_back(v ? 1 : 0); }
  void str(const std::string& s) {  // length counts the terminating NUL
    u32(static_cast<uint32_t>(s.size() + 1));
    bytes.insert(bytes.end(), s.begin(), s.end());
    bytes.push_back(0);
  }
};

struct CdrIn {
  const std::vector<uint8_t>& bytes;
  size_t at = 0;
  explicit CdrIn(const std::vector<uint8_t>& b) : bytes(b) {}
  void need(size_t n) {
    if (n > bytes.size() - at) throw std::runtime_error("CDR sample shorter than its type");
  }
  void align(size_t n) { at = (at + n - 1) / n * n; if (at > bytes.size()) need(1); }
  template <typename T> T raw() {
    align(sizeof(T));
    need(sizeof(T));
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  uint32_t u32() { return raw<uint32_t>(); }
  int32_t i32() { return raw<int32_t>(); }
  uint64_t u64() { return raw<uint64_t>(); }
  double f64() { return raw<double>(); }
  int8_t i8() { need(1); return static_cast<int8_t>(bytes[at++]); }
  bool boolean() { return i8() != 0; }
  std::string str() {
    uint32_t n = u32();
    need(n);
    if (n == 0 || bytes[at + n - 1] != 0) throw std::runtime_error("CDR string without NUL");
    std::string s(reinterpret_cast<const char*>(bytes.data() + at), n - 1);
    at += n;
    return s;
  }
  std::vector<double> f64_seq() {
    uint32_t n = u32();
    need(size_t(n) * 8);  // before allocating: a garbage length must not allocate gigabytes
    std::vector<double> v(n);
    for (auto& x : v) x = f64();
    return v;
  }
  std::vector<std::string> str_seq() {
    uint32_t n = u32();
    need(size_t(n) * 5);
    std::vector<std::string> v(n);
    for (auto& s : v) s = str();
    return v;
  }
};

// ---- The few ROS types the episode needs, field by field as in their .msg files -------------

struct Stamp {  // std_msgs/Header minus what we do not use
  int32_t sec = 0;
  uint32_t nanosec = 0;
  int64_t ns() const { return int64_t(sec) * 1000000000 + nanosec; }
};

Stamp read_header(CdrIn& in) {
  Stamp s;
  s.sec = in.i32();
  s.nanosec = in.u32();
  in.str();  // frame_id
  return s;
}

void write_header(CdrOut& out, const Stamp& s) {
  out.i32(s.sec);
  out.u32(s.nanosec);
  out.str("");
}

struct JointState {  // sensor_msgs/msg/JointState
  Stamp stamp;
  std::vector<std::string> name;
  std::vector<double> position;
};

JointState read_joint_state(CdrIn& in) {
  JointState js;
  js.stamp = read_header(in);
  js.name = in.str_seq();
  js.position = in.f64_seq();
  in.f64_seq();  // velocity
  in.f64_seq();  // effort
  return js;
}

std::vector<uint8_t> write_joint_state(const JointState& js) {
  CdrOut out;
  write_header(out, js.stamp);
  out.u32(uint32_t(js.name.size()));
  for (auto& n : js.name) out.str(n);
  out.u32(uint32_t(js.position.size()));
  for (double p : js.position) out.f64(p);
  out.u32(0);  // velocity
  out.u32(0);  // effort
  return out.bytes;
}

// composuite_msgs/msg/Observation: the five factors are fixed-size structs of float64 only
// (robot 32, object 14, obstacle 14, goal 17, task 16 values), then includes_task and flat.
constexpr int FACTOR_VALUES = 32 + 14 + 14 + 17 + 16;

struct Observation {
  Stamp stamp;
  uint32_t episode = 0, step = 0;
  std::vector<double> factors, flat;
  bool includes_task = false;
};

Observation read_observation(CdrIn& in) {
  Observation o;
  o.stamp = read_header(in);
  o.episode = in.u32();
  o.step = in.u32();
  for (int i = 0; i < FACTOR_VALUES; ++i) o.factors.push_back(in.f64());
  o.includes_task = in.boolean();
  o.flat = in.f64_seq();
  return o;
}

struct StagedReward {  // composuite_msgs/msg/StagedReward
  Stamp stamp;
  uint32_t episode = 0, step = 0;
  double total = 0;
  bool success = false;
};

StagedReward read_reward(CdrIn& in) {
  StagedReward r;
  r.stamp = read_header(in);
  r.episode = in.u32();
  r.step = in.u32();
  in.str();      // objective
  in.str_seq();  // stage_names
  in.f64_seq();  // stage_values
  in.f64_seq();  // stage_maxima
  in.i8();       // current_stage
  r.total = in.f64();
  r.success = in.boolean();
  return r;
}

std::vector<uint8_t> write_reset_request(uint64_t seed, bool use_seed) {  // Reset_Request
  CdrOut out;
  out.u64(seed);
  out.boolean(use_seed);
  return out.bytes;
}

struct ResetReply {  // Reset_Response
  bool success = false;
  std::string message;
  uint32_t episode = 0;
  uint64_t seed = 0;
  Observation observation;
};

ResetReply read_reset_reply(CdrIn& in) {
  ResetReply r;
  r.success = in.boolean();
  r.message = in.str();
  r.episode = in.u32();
  r.seed = in.u64();
  r.observation = read_observation(in);
  return r;
}

// ---- One TopicDataType for all: a sample is its CDR body; the functions above give it meaning.

struct Sample {
  std::vector<uint8_t> body;
};

class CdrType : public TopicDataType {
 public:
  explicit CdrType(const std::string& dds_name) {
    setName(dds_name.c_str());
    m_typeSize = 64 * 1024;  // upper bound of a sample here (an observation is ~1.6 kB)
    m_isGetKeyDefined = false;  // ROS topics have no keys
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }
  bool serialize(void* data, SerializedPayload_t* payload) override {
    auto* s = static_cast<Sample*>(data);
    uint32_t size = uint32_t(4 + s->body.size());
    if (payload->max_size < size) payload->reserve(size);
    // Encapsulation CDR_LE (0x0001), options 0, as rmw_fastrtps writes XCDR1.
    const uint8_t header[4] = {0x00, 0x01, 0x00, 0x00};
    std::memcpy(payload->data, header, 4);
    std::memcpy(payload->data + 4, s->body.data(), s->body.size());
    payload->length = size;
    payload->encapsulation = CDR_LE;
    return true;
  }
  bool deserialize(SerializedPayload_t* payload, void* data) override {
    if (payload->length < 4 || payload->data[0] != 0x00 || payload->data[1] != 0x01) {
      std::fprintf(stderr, "peer: %s sample not CDR little endian, dropped\n", getName());
      return false;
    }
    auto* s = static_cast<Sample*>(data);
    s->body.assign(payload->data + 4, payload->data + payload->length);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    auto* s = static_cast<Sample*>(data);
    return [s]() { return uint32_t(4 + s->body.size()); };
  }
  void* createData() override { return new Sample(); }
  void deleteData(void* data) override { delete static_cast<Sample*>(data); }
  bool getKey(void*, InstanceHandle_t*, bool) override { return false; }
};

// ---- Output --------------------------------------------------------------------------------

std::string hex(double v) {  // what Python's struct.pack("<d", v).hex() gives
  uint8_t b[8];
  std::memcpy(b, &v, 8);
  char out[17];
  for (int i = 0; i < 8; ++i) std::snprintf(out + 2 * i, 3, "%02x", b[i]);
  return std::string(out, 16);
}

std::string hex_list(const std::vector<double>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ",\"" : "\"") + hex(v[i]) + "\"";
  return s + "]";
}

std::string json_str(const std::string& s) {  // names and messages here are plain ASCII
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o + "\"";
}

[[noreturn]] void fail(const std::string& why) {
  Log::Flush();  // Fast DDS logs from a thread of its own: its reason first
  std::fprintf(stderr, "peer: FAILED: %s\n", why.c_str());
  std::fflush(stderr);
  std::_Exit(1);  // skip destructors: a half-made participant may block in its teardown
}

using Clock = std::chrono::steady_clock;

struct Args {
  int domain = 0;
  std::string ns, enclave;
  uint64_t seed = 0;
  int steps = 0;
  double expect_no_suite = 0;
  bool verbose = false;
  bool second_reader = false;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) fail("missing value of " + k);
      return argv[++i];
    };
    if (k == "--domain") a.domain = std::stoi(value());
    else if (k == "--namespace") a.ns = value();
    else if (k == "--enclave") a.enclave = value();
    else if (k == "--seed") a.seed = std::stoull(value());
    else if (k == "--steps") a.steps = std::stoi(value());
    else if (k == "--expect-no-suite") a.expect_no_suite = std::stod(value());
    else if (k == "--verbose") a.verbose = true;
    else if (k == "--second-observation-reader") a.second_reader = true;
    else fail("unknown argument " + k);
  }
  if (a.ns.empty() || a.ns[0] != '/') fail("--namespace must be a fully qualified name");
  if (a.ns == "/") a.ns = "";
  return a;
}

// A GUID prefix as RustDDS's logs write it: 24 hex digits.
std::string hex_prefix(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) {
  char text[2 * 12 + 1];
  for (int i = 0; i < 12; ++i) std::snprintf(text + 2 * i, 3, "%02x", prefix.value[i]);
  return text;
}

// Says on stderr how each remote participant's authentication ended (Debian's Fast DDS logs no
// info records, and a refused handshake is otherwise silent): the suite's DDS logs name
// participants by GUID prefix, so a test's failure message can tell which pair never trusted
// each other.
struct AuthenticationReport : DomainParticipantListener {
  void onParticipantAuthentication(
      DomainParticipant*, eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) override {
    const bool ok =
        info.status == eprosima::fastrtps::rtps::ParticipantAuthenticationInfo::AUTHORIZED_PARTICIPANT;
    std::fprintf(stderr, "peer: %s participant %s\n", ok ? "authenticated" : "REFUSED",
                 hex_prefix(info.guid.guidPrefix).c_str());
  }
};

// The participant as rmw_fastrtps makes it from an enclave folder (rmw_dds_common's file
// names, properties as rmw_fastrtps sets them), on UDPv4 only: no shared-memory transport, so
// the peer cannot reach Fast DDS processes outside its network namespace through /dev/shm.
DomainParticipant* make_participant(const Args& a) {
  DomainParticipantQos qos = PARTICIPANT_QOS_DEFAULT;
  qos.name("fastdds_secure_peer");
  qos.transport().use_builtin_transports = false;
  qos.transport().user_transports.push_back(
      std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>());
  if (!a.enclave.empty()) {
    auto& p = qos.properties().properties();
    auto file = [&](const char* name) { return "file://" + a.enclave + "/" + name; };
    p.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
    p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", file("identity_ca.cert.pem"));
    p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate", file("cert.pem"));
    p.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", file("key.pem"));
    p.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
    p.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions_ca",
                   file("permissions_ca.cert.pem"));
    p.emplace_back("dds.sec.access.builtin.Access-Permissions.governance", file("governance.p7s"));
    p.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions",
                   file("permissions.p7s"));
    p.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  }
  static AuthenticationReport report;
  auto* participant = DomainParticipantFactory::get_instance()->create_participant(
      a.domain, qos, &report, StatusMask::none());
  if (participant == nullptr) fail("create_participant refused (security files or domain?)");
  return participant;
}

struct Endpoints {
  DomainParticipant* participant;
  Publisher* publisher;
  Subscriber* subscriber;
  std::map<std::string, TypeSupport> types;
  std::map<std::string, Topic*> topics;

  Topic* topic(const std::string& name, const std::string& type) {
    if (!types.count(type)) {
      types[type] = TypeSupport(new CdrType(type));
      if (types[type].register_type(participant) != ReturnCode_t::RETCODE_OK)
        fail("register_type " + type);
    }
    if (topics.count(name)) return topics[name];  // one Topic per name and participant
    Topic* t = participant->create_topic(name, type, TOPIC_QOS_DEFAULT);
    if (t == nullptr) fail("create_topic " + name);
    return topics[name] = t;
  }
  // ROS's default QoS (and rmw_qos_profile_services_default): reliable, volatile, keep last 10.
  template <class Qos>
  static Qos ros_default(Qos q) {
    q.reliability().kind = RELIABLE_RELIABILITY_QOS;
    q.durability().kind = VOLATILE_DURABILITY_QOS;
    q.history().kind = KEEP_LAST_HISTORY_QOS;
    q.history().depth = 10;
    q.endpoint().history_memory_policy =
        eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
    return q;
  }
  DataWriter* writer(const std::string& name, const std::string& type) {
    DataWriterQos q = ros_default(DATAWRITER_QOS_DEFAULT);
    DataWriter* w = publisher->create_datawriter(topic(name, type), q);
    if (w == nullptr) fail("not allowed to create a DataWriter to topic " + name);
    return w;
  }
  DataReader* reader(const std::string& name, const std::string& type) {
    DataReaderQos q = ros_default(DATAREADER_QOS_DEFAULT);
    DataReader* r = subscriber->create_datareader(topic(name, type), q);
    if (r == nullptr) fail("not allowed to create a DataReader to topic " + name);
    return r;
  }
};

}  // namespace

int main(int argc, char** argv) {
  Args a = parse(argc, argv);
  // Fast DDS logs warnings to stdout by default; stdout is the episode's, so all of it to stderr.
  Log::ClearConsumers();
  auto consumer = std::make_unique<StdoutErrConsumer>();
  consumer->stderr_threshold(Log::Kind::Info);
  Log::RegisterConsumer(std::move(consumer));
  if (a.verbose) {
    Log::SetVerbosity(Log::Kind::Info);
    Log::SetCategoryFilter(std::regex(".*"));
  } else {
    Log::SetVerbosity(Log::Kind::Warning);
  }
  auto* participant = make_participant(a);
  // The suite's DDS logs name remote participants by GUID prefix: say which one is ours.
  std::fprintf(stderr, "peer: participant %s\n", hex_prefix(participant->guid().guidPrefix).c_str());
  Endpoints e{participant, participant->create_publisher(PUBLISHER_QOS_DEFAULT),
              participant->create_subscriber(SUBSCRIBER_QOS_DEFAULT), {}, {}};
  const std::string js_type = "sensor_msgs::msg::dds_::JointState_";
  DataWriter* command = e.writer("rt" + a.ns + "/joint_command", js_type);
  DataReader* states = e.reader("rt" + a.ns + "/joint_states", js_type);
  DataReader* observations =
      e.reader("rt" + a.ns + "/observation", "composuite_msgs::msg::dds_::Observation_");
  DataReader* rewards =
      e.reader("rt" + a.ns + "/reward", "composuite_msgs::msg::dds_::StagedReward_");
  // A second subscription to the same topic in this participant, as a ROS node with two
  // subscriptions (or two nodes of one context) has: the report says what it received.
  DataReader* observations2 =
      a.second_reader
          ? e.reader("rt" + a.ns + "/observation", "composuite_msgs::msg::dds_::Observation_")
          : nullptr;
  size_t second_reader_samples = 0;
  DataWriter* request =
      e.writer("rq" + a.ns + "/resetRequest", "composuite_msgs::srv::dds_::Reset_Request_");
  DataReader* reply =
      e.reader("rr" + a.ns + "/resetReply", "composuite_msgs::srv::dds_::Reset_Response_");

  // Everything the suite sends, kept by what it is about: observations and rewards by
  // (episode, step), joint_states by stamp, reset replies by the request they answer.
  std::map<std::pair<uint32_t, uint32_t>, Observation> obs;
  std::map<std::pair<uint32_t, uint32_t>, StagedReward> rew;
  std::map<int64_t, JointState> js;
  std::map<int64_t, ResetReply> replies;  // by the request's sequence number
  auto take_all = [&]() {
    Sample s;
    SampleInfo info;
    auto each = [&](DataReader* r, const std::function<void(CdrIn&)>& use) {
      while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        CdrIn in(s.body);
        try {
          use(in);
        } catch (const std::exception& err) {
          fail(std::string(r->get_topicdescription()->get_name()) + ": " + err.what());
        }
      }
    };
    each(states, [&](CdrIn& in) { auto j = read_joint_state(in); js[j.stamp.ns()] = j; });
    each(observations, [&](CdrIn& in) {
      auto o = read_observation(in);
      obs[{o.episode, o.step}] = o;
    });
    if (observations2 != nullptr)
      each(observations2, [&](CdrIn& in) { read_observation(in); ++second_reader_samples; });
    each(rewards, [&](CdrIn& in) {
      auto r = read_reward(in);
      rew[{r.episode, r.step}] = r;
    });
    each(reply, [&](CdrIn& in) {
      // rmw_fastrtps' mapping: the reply names the request in related_sample_identity.
      replies[info.related_sample_identity.sequence_number().to64long()] = read_reset_reply(in);
    });
  };
  auto wait_for = [&](double seconds, const std::function<bool()>& done) {
    auto end = Clock::now() + std::chrono::duration<double>(seconds);
    while (true) {
      take_all();
      if (done()) return true;
      if (Clock::now() >= end) return false;
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  };
  // Each of our endpoints by its topic, and whether it has matched one of the suite's. A
  // failure names those that have not, so a refusal (or a key exchange that never finished)
  // points at its topic.
  auto endpoints = [&]() {
    PublicationMatchedStatus p;
    SubscriptionMatchedStatus s;
    std::vector<std::pair<std::string, bool>> all;
    for (DataWriter* w : {command, request})
      all.emplace_back(w->get_topic()->get_name(),
                       w->get_publication_matched_status(p) == ReturnCode_t::RETCODE_OK && p.current_count > 0);
    for (DataReader* r : {states, observations, rewards, reply})
      all.emplace_back(r->get_topicdescription()->get_name(),
                       r->get_subscription_matched_status(s) == ReturnCode_t::RETCODE_OK && s.current_count > 0);
    return all;
  };
  auto matched = [&]() {
    int n = 0;
    for (const auto& [name, is_matched] : endpoints()) n += is_matched;
    return n;
  };
  auto unmatched = [&]() {
    std::string names;
    for (const auto& [name, is_matched] : endpoints())
      if (!is_matched) names += " " + name;
    return names;
  };

  if (a.expect_no_suite > 0) {
    // A peer the secured suite must not talk to: nothing may match, nothing may arrive.
    wait_for(a.expect_no_suite, [] { return false; });
    std::printf("{\"matched\":%d,\"observations\":%zu,\"joint_states\":%zu}\n", matched(),
                obs.size(), js.size());
    std::fflush(stdout);
    Log::Flush();
    std::_Exit(matched() == 0 && obs.empty() && js.empty() ? 0 : 1);
  }

  if (!wait_for(30.0, [&] { return matched() == 6; }))
    fail("the suite's endpoints did not all match within 30 s (" + std::to_string(matched()) +
         " of 6; not matched:" + unmatched() + "): authentication or access control refused?");
  std::fprintf(stderr, "peer: all 6 endpoints matched\n");

  // A reset as rmw_fastrtps' client sends it: the reply reader's GUID in the request's
  // related_sample_identity, our own sample identity the key of the answer. A reply can be lost
  // before the server's reply writer matched our reader: ask again after 3 s.
  auto reset = [&](uint64_t seed, bool use_seed) -> ResetReply {
    for (int attempt = 0; attempt < 5; ++attempt) {
      Sample s{write_reset_request(seed, use_seed)};
      WriteParams params;
      params.related_sample_identity().writer_guid() = reply->guid();
      if (!request->write(&s, params)) fail("writing the reset request");
      int64_t seq = params.sample_identity().sequence_number().to64long();
      if (wait_for(3.0, [&] { return replies.count(seq) > 0; })) {
        ResetReply r = replies[seq];
        if (!r.success) fail("reset refused: " + r.message);
        return r;
      }
      std::fprintf(stderr, "peer: no reset reply within 3 s, asking again\n");
    }
    fail("reset never answered");
  };
  auto send = [&](const std::vector<std::string>& names, const std::vector<double>& targets,
                  const Stamp& answers) {
    Sample s{write_joint_state(JointState{answers, names, targets})};
    if (!command->write(&s)) fail("writing joint_command");
  };

  // Warm-up: a volatile sample a node writes before it knows our reader is lost, and each side
  // sees a match on its own; reset and step until a step's observation and reward both came.
  bool warm = false;
  for (int i = 0; i < 10 && !warm; ++i) {
    ResetReply r = reset(0, false);
    int64_t stamp = r.observation.stamp.ns();
    if (!wait_for(1.0, [&] { return js.count(stamp) > 0; })) continue;
    const JointState& first = js[stamp];
    send({first.name.begin(), first.name.begin() + 7},
         {first.position.begin(), first.position.begin() + 7}, r.observation.stamp);
    std::pair<uint32_t, uint32_t> key{r.episode, 1};
    warm = wait_for(1.0, [&] { return obs.count(key) && rew.count(key); });
  }
  if (!warm) fail("observation, reward and joint_states never all arrived");
  std::fprintf(stderr, "peer: warmed up\n");

  ResetReply r = reset(a.seed, true);
  if (r.seed != a.seed || r.observation.step != 0 || r.observation.episode != r.episode)
    fail("reset answered another episode");
  const uint32_t episode = r.episode;
  int64_t stamp0 = r.observation.stamp.ns();
  if (!wait_for(5.0, [&] { return js.count(stamp0) > 0; })) fail("no joint_states of the reset");
  const JointState start = js[stamp0];
  std::vector<std::string> arm;
  std::vector<double> pose;
  for (size_t i = 0; i < start.name.size(); ++i) {
    const std::string& n = start.name[i];
    if (n.size() >= 12 && n.compare(n.size() - 12, 12, "finger_joint") == 0) continue;
    arm.push_back(n);
    pose.push_back(start.position.at(i));
  }
  if (arm.size() != 7) fail("expected 7 arm joints in joint_states");
  std::string names = "[";
  for (size_t i = 0; i < arm.size(); ++i) names += (i ? "," : "") + json_str(arm[i]);
  std::printf("{\"episode\":%u,\"seed\":%llu,\"arm\":%s]}\n", episode,
              static_cast<unsigned long long>(r.seed), names.c_str());
  std::printf("{\"step\":0,\"stamp_ns\":%lld,\"flat\":%s}\n",
              static_cast<long long>(stamp0), hex_list(r.observation.flat).c_str());
  std::fflush(stdout);

  // The episode: a smooth sweep around the start pose, each command answering the latest
  // observation; the test replays exactly these targets in the in-process env.
  Stamp answers = r.observation.stamp;
  for (int k = 1; k <= a.steps; ++k) {
    std::vector<double> targets;
    for (size_t j = 0; j < pose.size(); ++j)
      targets.push_back(pose[j] + 0.3 * std::sin(0.1 * k + double(j)));
    send(arm, targets, answers);
    std::pair<uint32_t, uint32_t> key{episode, uint32_t(k)};
    if (!wait_for(5.0, [&] { return obs.count(key) && rew.count(key); }))
      fail("no observation and reward of step " + std::to_string(k));
    const Observation& o = obs[key];
    const StagedReward& w = rew[key];
    std::printf(
        "{\"step\":%d,\"stamp_ns\":%lld,\"reward_stamp_ns\":%lld,\"command\":%s,\"flat\":%s,"
        "\"reward\":\"%s\",\"success\":%s}\n",
        k, static_cast<long long>(o.stamp.ns()), static_cast<long long>(w.stamp.ns()),
        hex_list(targets).c_str(), hex_list(o.flat).c_str(), hex(w.total).c_str(),
        w.success ? "true" : "false");
    std::fflush(stdout);
    answers = o.stamp;
  }
  std::fprintf(stderr, "peer: episode of %d steps done\n", a.steps);
  if (observations2 != nullptr)
    std::printf("{\"second_reader_observations\":%zu}\n", second_reader_samples);
  std::fflush(stderr);
  // Leave the graph cleanly so the suite sees us go rather than time out.
  participant->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant);
  return 0;
}
