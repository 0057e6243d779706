#include "dreamsense/publish/dds_publisher.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/export/primitive_json.hpp"

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>

#include "ros_hri.hpp"

#ifdef DREAMSENSE_HAVE_DDS
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#endif

namespace dreamsense::publish {

namespace {

bool is_primitive_name(const std::string& name) {
  for (const auto& i : primitives::catalogue())
    if (name == i.name) return true;
  return false;
}

}  // namespace

std::string dds_topic_token(const std::string& primitive) {
  // ROS 2 name tokens are [A-Za-z0-9_]: "getHeadGaze (plane)" -> "getHeadGaze_plane".
  std::string out;
  for (char c : primitive) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (ok)
      out += c;
    else if (!out.empty() && out.back() != '_')
      out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

Status DdsPublisherOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  // ROS 2 / DDS: domain ids 0-232 map to valid UDP ports.
  if (domain_id < 0 || domain_id > 232)
    add(fmt::format("domain_id must be in [0, 232] (is {})", domain_id));
  if (topic_prefix.empty() || topic_prefix.front() == '/' || topic_prefix.back() == '/')
    add(fmt::format("topic_prefix must be a non-empty name without leading/trailing '/' (is '{}')",
                    topic_prefix));
  for (const auto& name : only)
    if (!is_primitive_name(name)) add(fmt::format("'{}' is not a primitive name", name));
  if (!ros_topics && !json_topics) add("nothing to publish (ros_topics and json_topics both off)");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "DdsPublisherOptions: {}", bad);
  return ok_status();
}

std::string dds_topic_name(const DdsPublisherOptions& options, const std::string& primitive) {
  return "rt/" + options.topic_prefix + "/" + dds_topic_token(primitive);
}

#ifdef DREAMSENSE_HAVE_DDS
namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

struct StringMessage {
  std::string data;
};

// ROS 2 std_msgs/msg/String: one CDR string. Written little-endian with its encapsulation header.
class StringType : public dds::TopicDataType {
 public:
  StringType() {
    setName(kDdsStringTypeName);
    m_typeSize = 4 + 4 + 64 * 1024;  // encapsulation + length + a generous bound (reallocated)
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    const auto* m = static_cast<StringMessage*>(data);
    const uint32_t n = static_cast<uint32_t>(m->data.size() + 1);  // with the terminating 0
    const uint32_t size = 4 + 4 + n;
    if (payload->max_size < size) payload->reserve(size);
    uint8_t* p = payload->data;
    p[0] = 0x00;
    p[1] = 0x01;  // CDR_LE
    p[2] = p[3] = 0;
    for (int i = 0; i < 4; ++i) p[4 + i] = static_cast<uint8_t>(n >> (8 * i));
    std::memcpy(p + 8, m->data.c_str(), n);
    payload->length = size;
    payload->encapsulation = CDR_LE;
    return true;
  }
  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    if (payload->length < 8) return false;
    const uint8_t* p = payload->data;
    const bool little = p[1] == 0x01;
    uint32_t n = 0;
    for (int i = 0; i < 4; ++i) n |= static_cast<uint32_t>(p[4 + (little ? i : 3 - i)]) << (8 * i);
    if (n == 0 || 8 + n > payload->length) return false;
    static_cast<StringMessage*>(data)->data.assign(reinterpret_cast<const char*>(p + 8), n - 1);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] {
      return static_cast<uint32_t>(8 + static_cast<StringMessage*>(data)->data.size() + 1);
    };
  }
  void* createData() override { return new StringMessage(); }
  void deleteData(void* data) override { delete static_cast<StringMessage*>(data); }
  bool getKey(void*, rtps::InstanceHandle_t*, bool) override { return false; }
};

// A participant limited to this machine unless options.network (spec/system.md: network exposure
// is opt-in).
dds::DomainParticipant* make_participant(const DdsPublisherOptions& o, const std::string& name) {
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name(name);
  if (!o.network) {
    qos.transport().use_builtin_transports = false;
    qos.transport().user_transports.push_back(
        std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>());
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    qos.transport().user_transports.push_back(udp);
  }
  return dds::DomainParticipantFactory::get_instance()->create_participant(
      static_cast<dds::DomainId_t>(o.domain_id), qos);
}

dds::TopicQos topic_qos() { return dds::TOPIC_QOS_DEFAULT; }

}  // namespace

struct DdsPublisher::Impl {
  DdsPublisherOptions options;
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::TypeSupport type{new StringType()};
  std::map<std::string, std::pair<dds::Topic*, dds::DataWriter*>> writers;  // by topic name
#ifdef DREAMSENSE_HAVE_ROS_MSGS
  detail::RosHriTopics ros;
#endif
  mutable std::mutex mutex;
  DdsPublisherStats stats;

  ~Impl() {
    if (participant == nullptr) return;
    // Reliable delivery of the last samples to readers already matched, bounded so a vanished
    // reader cannot hold the shutdown.
    for (auto& [name, topic_writer] : writers)
      if (topic_writer.second != nullptr)
        topic_writer.second->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(1, 0));
    participant->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
  }

  dds::DataWriter* writer_for(const std::string& topic_name, dds::TypeSupport& topic_type) {
    auto it = writers.find(topic_name);
    if (it != writers.end()) return it->second.second;
    dds::Topic* topic =
        participant->create_topic(topic_name, topic_type.get_type_name(), topic_qos());
    if (topic == nullptr) return nullptr;
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    wq.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    wq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    wq.history().depth = 10;
    // Transient-local: a reader whose discovery completes late (a loaded machine) still gets the
    // last `depth` samples; volatile readers (the ROS 2 default) match it as well.
    wq.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
    wq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    dds::DataWriter* w = publisher->create_datawriter(topic, wq);
    writers[topic_name] = {topic, w};
    return w;
  }
};

DdsPublisher::DdsPublisher(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsPublisher::~DdsPublisher() = default;

Result<std::unique_ptr<DdsPublisher>> DdsPublisher::create(const DdsPublisherOptions& options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  if (options.ros_topics && !have_ros_messages())
    return make_error(
        ErrorCode::kUnsupported,
        "DDS: typed ROS 2 messages are not in this build (install Debian's fastddsgen "
        "and rebuild), or publish the JSON topics only");
  auto m = std::make_unique<Impl>();
  m->options = options;
  m->participant = make_participant(options, "dreamsense");
  if (m->participant == nullptr)
    return make_error(ErrorCode::kIoError, "DDS: cannot create a participant in domain {}",
                      options.domain_id);
  if (m->type.register_type(m->participant) != ReturnCode_t::RETCODE_OK)
    return make_error(ErrorCode::kInternal, "DDS: cannot register type {}", kDdsStringTypeName);
#ifdef DREAMSENSE_HAVE_ROS_MSGS
  if (options.ros_topics) DS_RETURN_IF_ERROR(m->ros.register_types(m->participant));
#endif
  m->publisher = m->participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  if (m->publisher == nullptr)
    return make_error(ErrorCode::kIoError, "DDS: cannot create a publisher");
  log::info("DDS: publishing {}{}{} (domain {}, {})",
            options.ros_topics
                ? "ROS4HRI topics rt/humans/... and rt/" + options.topic_prefix + "/mutual_gaze"
                : "",
            options.ros_topics && options.json_topics ? " and " : "",
            options.json_topics ? "JSON topics rt/" + options.topic_prefix + "/<primitive>" : "",
            options.domain_id, options.network ? "all network interfaces" : "this machine only");
  if (options.network)
    log::warn(
        "DDS: --dds-network: the session's primitives (where the child is and looks, what "
        "is said) are visible to every machine on this network");
  return std::unique_ptr<DdsPublisher>(new DdsPublisher(std::move(m)));
}

Status DdsPublisher::publish(const std::vector<primitives::PrimitiveRecord>& records) {
  Impl& m = *impl_;
  std::lock_guard lock(m.mutex);
#ifdef DREAMSENSE_HAVE_ROS_MSGS
  if (m.options.ros_topics)
    DS_RETURN_IF_ERROR(m.ros.publish(
        records, m.options,
        [&m](const std::string& topic, dds::TypeSupport& type) {
          return m.writer_for(topic, type);
        },
        m.stats));
#endif
  if (!m.options.json_topics) return ok_status();
  for (const auto& r : records) {
    if (!m.options.all_statuses && r.status != primitives::PrimitiveStatus::kOk) continue;
    const std::string name = primitives::info(r.id).name;
    if (!m.options.only.empty() && !m.options.only.count(name)) continue;
    dds::DataWriter* w = m.writer_for(dds_topic_name(m.options, name), m.type);
    if (w == nullptr)
      return make_error(ErrorCode::kIoError, "DDS: cannot create the writer of {}",
                        dds_topic_name(m.options, name));
    StringMessage msg{exporters::to_json(r).dump()};
    if (w->write(&msg))
      ++m.stats.published;
    else
      ++m.stats.failed;
  }
  return ok_status();
}

DdsPublisherStats DdsPublisher::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

struct DdsStringSubscriber::Impl : public dds::DataReaderListener {
  dds::DomainParticipant* participant = nullptr;
  dds::TypeSupport type{new StringType()};
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<std::string> received;

  ~Impl() override {
    if (participant == nullptr) return;
    participant->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
  }
  void on_data_available(dds::DataReader* reader) override {
    StringMessage msg;
    dds::SampleInfo info;
    while (reader->take_next_sample(&msg, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard lock(mutex);
      received.push_back(msg.data);
      cv.notify_all();
    }
  }
};

DdsStringSubscriber::DdsStringSubscriber(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsStringSubscriber::~DdsStringSubscriber() = default;

Result<std::unique_ptr<DdsStringSubscriber>> DdsStringSubscriber::create(
    const DdsPublisherOptions& options, const std::string& primitive) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  auto m = std::make_unique<Impl>();
  m->participant = make_participant(options, "dreamsense-subscriber");
  if (m->participant == nullptr)
    return make_error(ErrorCode::kIoError, "DDS: cannot create a participant in domain {}",
                      options.domain_id);
  m->type.register_type(m->participant);
  dds::Topic* topic = m->participant->create_topic(dds_topic_name(options, primitive),
                                                   m->type.get_type_name(), topic_qos());
  dds::Subscriber* sub = m->participant->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  if (topic == nullptr || sub == nullptr)
    return make_error(ErrorCode::kIoError, "DDS: cannot subscribe to {}",
                      dds_topic_name(options, primitive));
  dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
  rq.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  rq.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
  rq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  rq.history().depth = 100;
  rq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
  if (sub->create_datareader(topic, rq, m.get()) == nullptr)
    return make_error(ErrorCode::kIoError, "DDS: cannot create a reader on {}",
                      dds_topic_name(options, primitive));
  return std::unique_ptr<DdsStringSubscriber>(new DdsStringSubscriber(std::move(m)));
}

std::vector<std::string> DdsStringSubscriber::wait_for(size_t count, int timeout_ms) {
  std::unique_lock lock(impl_->mutex);
  impl_->cv.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                     [&] { return impl_->received.size() >= count; });
  return impl_->received;
}

#else  // no Fast DDS in this build

struct DdsPublisher::Impl {};
DdsPublisher::DdsPublisher(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsPublisher::~DdsPublisher() = default;
Result<std::unique_ptr<DdsPublisher>> DdsPublisher::create(const DdsPublisherOptions&) {
  return make_error(ErrorCode::kUnsupported,
                    "DDS publishing is not in this build (install libfastrtps-dev and rebuild)");
}
Status DdsPublisher::publish(const std::vector<primitives::PrimitiveRecord>&) {
  return make_error(ErrorCode::kUnsupported, "DDS publishing is not in this build");
}
DdsPublisherStats DdsPublisher::stats() const { return {}; }
struct DdsStringSubscriber::Impl {};
DdsStringSubscriber::DdsStringSubscriber(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsStringSubscriber::~DdsStringSubscriber() = default;
Result<std::unique_ptr<DdsStringSubscriber>> DdsStringSubscriber::create(const DdsPublisherOptions&,
                                                                         const std::string&) {
  return make_error(ErrorCode::kUnsupported, "DDS is not in this build");
}
std::vector<std::string> DdsStringSubscriber::wait_for(size_t, int) { return {}; }

#endif

}  // namespace dreamsense::publish
