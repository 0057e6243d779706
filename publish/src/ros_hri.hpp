#pragma once
// The typed ROS 2 topics (ROS4HRI / REP-155 and dreamsense_msgs) of one tick's primitive records,
// written through the DdsPublisher's participant (private to the publish library).

#include "dreamsense/publish/dds_publisher.hpp"

#include <functional>
#include <memory>

#ifdef DREAMSENSE_HAVE_ROS_MSGS
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

namespace dreamsense::publish::detail {

// The writer of `topic` with `type` (created on first use); null when DDS refuses it.
using WriterLookup = std::function<eprosima::fastdds::dds::DataWriter*(
    const std::string& topic, eprosima::fastdds::dds::TypeSupport& type)>;

class RosHriTopics {
 public:
  RosHriTopics();
  ~RosHriTopics();
  Status register_types(eprosima::fastdds::dds::DomainParticipant* participant);
  // Writes the messages of one tick's records (every record of the tick is needed: the face id
  // comes from trackFace, the voice id from identifyVoice).
  Status publish(const std::vector<primitives::PrimitiveRecord>& records,
                 const DdsPublisherOptions& options, const WriterLookup& writer,
                 DdsPublisherStats& stats);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::publish::detail
#endif
