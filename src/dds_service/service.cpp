#include "usv_fdi/dds_service/service.hpp"

#include <atomic>
#include <stdexcept>
#include <vector>

#include "usv_fdi/dds_service/convert.hpp"

namespace usvfdi::service {

namespace dds = usv_fdi::dds;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::DataReaderListener;
using eprosima::fastdds::dds::StatusMask;

/// Reader listener: copies this vessel's samples into the pipeline's input queue, nothing else
/// (no I/O, no locks held across calls; the queue never blocks).
class FdiService::Listener : public DataReaderListener {
 public:
  Listener(FdiPipeline* p, std::uint32_t mmsi) : p_(p), mmsi_(mmsi) {}
  void on_data_available(DataReader* reader) override {
    if (reader == ins_) {
      ins_buf_.clear();
      dds::take_all(*reader, ins_buf_);
      for (const auto& s : ins_buf_) {
        if (s.mmsi() == mmsi_) p_->push_ins(from_dds(s));
      }
    } else if (reader == rudder_) {
      rudder_buf_.clear();
      dds::take_all(*reader, rudder_buf_);
      for (const auto& s : rudder_buf_) {
        if (s.mmsi() == mmsi_) p_->push_rudder(from_dds(s));
      }
    } else if (reader == ack_) {
      ack_buf_.clear();
      dds::take_all(*reader, ack_buf_);
      for (const auto& a : ack_buf_) {
        if (a.mmsi() == mmsi_) p_->push_ack(from_dds(a));
      }
    }
  }
  DataReader* ins_ = nullptr;
  DataReader* rudder_ = nullptr;
  DataReader* ack_ = nullptr;

 private:
  FdiPipeline* p_;
  std::uint32_t mmsi_;
  // Each reader's callbacks are serialised by Fast DDS; one buffer per reader.
  std::vector<fdi::InsSample> ins_buf_;
  std::vector<fdi::RudderSample> rudder_buf_;
  std::vector<fdi::FaultAck> ack_buf_;
};

FdiService::FdiService(const ServiceConfig& cfg, LogSink log) : cfg_(cfg), log_(std::move(log)) {
  if (cfg_.mmsi == 0) throw std::invalid_argument("service.mmsi must be set (a vessel's MMSI > 0)");
  dds_ = std::make_unique<dds::DdsContext>(cfg_.dds);
  event_writer_ = &dds_->create_writer(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventWriter);
  status_writer_ = &dds_->create_writer(dds::TopicId::kStatus, dds::profiles::kStatusWriter);
  const std::uint32_t mmsi = cfg_.mmsi;
  const IsolationParams iso = cfg_.engine.isolation;
  auto on_event = [this, mmsi](const FaultEvent& e) {
    dds::write(*event_writer_, to_dds(e, mmsi));
    if (log_) {
      log_(1, std::string("event #") + std::to_string(e.sequence) + " " + to_string(e.sensor) +
                  " " + to_string(e.state) + " kind=" + to_string(e.kind) +
                  " C_a=" + std::to_string(e.c_a) + " C_g=" + std::to_string(e.c_g) +
                  " t=" + std::to_string(e.t) + ": " + e.message);
    }
  };
  auto on_status = [this, mmsi, iso](const PipelineStatus& s) {
    dds::write(*status_writer_, to_dds(s, mmsi, iso));
  };
  pipeline_ = std::make_unique<FdiPipeline>(cfg_.engine, cfg_.pipeline, on_event, on_status, log_);
  listener_ = std::make_unique<Listener>(pipeline_.get(), mmsi);
  DataReader& ins = dds_->create_reader(dds::TopicId::kIns,
                                        cfg_.reliable_inputs ? dds::profiles::kInsReaderReliable
                                                             : dds::profiles::kInsReaderBestEffort);
  DataReader& rudder = dds_->create_reader(
      dds::TopicId::kRudder, cfg_.reliable_inputs ? dds::profiles::kRudderReaderReliable
                                                  : dds::profiles::kRudderReaderBestEffort);
  DataReader& ack = dds_->create_reader(dds::TopicId::kFaultAck, dds::profiles::kFaultAckReader);
  listener_->ins_ = &ins;
  listener_->rudder_ = &rudder;
  listener_->ack_ = &ack;
}

FdiService::~FdiService() { stop(); }

void FdiService::start() {
  pipeline_->start();
  // Listeners are attached only now, so nothing arrives before the threads run.
  for (DataReader* r : {listener_->ins_, listener_->rudder_, listener_->ack_}) {
    r->set_listener(listener_.get(), StatusMask::data_available());
  }
}

void FdiService::stop() {
  if (stopped_) return;
  stopped_ = true;
  for (DataReader* r : {listener_->ins_, listener_->rudder_, listener_->ack_}) {
    if (r != nullptr) r->set_listener(nullptr);
  }
  pipeline_->stop();  // drains the queues; the publisher thread writes the last events
  dds_.reset();       // delete_contained_entities(), then the participant
}

}  // namespace usvfdi::service
