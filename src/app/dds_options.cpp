#include "dds_options.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/log/Log.hpp>

#include <csignal>
#include <ctime>
#include <memory>

#include "usv_fdi/core/text.hpp"
#include "usv_fdi/dds_service/service.hpp"

namespace usvfdi::app {

void add_dds_options(CLI::App* sub, DdsCli* cli, bool with_config) {
  if (with_config) {
    sub->add_option("--config", cli->config, "service YAML; its service: section sets DDS")
        ->check(CLI::ExistingFile);
  }
  sub->add_option("--domain", cli->domain, "DDS domain id (overrides the config)")
      ->check(CLI::Range(0, 232));
  sub->add_option("--qos", cli->qos, "Fast DDS XML profiles file (overrides the config)")
      ->check(CLI::ExistingFile);
  sub->add_option("--participant-profile", cli->participant_profile,
                  "participant profile in the XML (e.g. usv_fdi_participant_loopback)");
  sub->add_option("--partition", cli->partitions, "DDS partition (repeatable)");
}

usvfdi::dds::DdsConfig make_dds_config(const DdsCli& cli, bool* reliable_inputs) {
  usvfdi::dds::DdsConfig d;
  bool reliable = cli.reliable;
  if (!cli.config.empty()) {
    const dds_service::ServiceConfig s = dds_service::load_service_config(cli.config);
    d = s.dds;
    reliable = reliable || s.reliable_inputs;
  } else {
    // Same defaults as a config without a service section.
    d.profiles_file = dds_service::default_qos_profiles();
  }
  if (cli.domain) d.domain_id = *cli.domain;
  if (!cli.qos.empty()) d.profiles_file = cli.qos;
  if (!cli.participant_profile.empty()) d.participant_profile = cli.participant_profile;
  if (!cli.partitions.empty()) {
    d.publisher_partitions = cli.partitions;
    d.subscriber_partitions = cli.partitions;
  }
  if (reliable_inputs) *reliable_inputs = reliable;
  return d;
}

void block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

int wait_for_stop_signal(double timeout_s) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  timespec ts;
  ts.tv_sec = static_cast<time_t>(timeout_s);
  ts.tv_nsec = static_cast<long>((timeout_s - static_cast<double>(ts.tv_sec)) * 1e9);
  const int sig = sigtimedwait(&set, nullptr, &ts);
  return sig > 0 ? sig : 0;
}

namespace {

class SpdlogConsumer : public eprosima::fastdds::dds::LogConsumer {
 public:
  void Consume(const eprosima::fastdds::dds::Log::Entry& e) override {
    using Kind = eprosima::fastdds::dds::Log::Kind;
    // Fast DDS's messages may quote what a peer sent (partition, topic, type names): escaped.
    const std::string category =
        escape_text(e.context.category != nullptr ? e.context.category : "?");
    const std::string message = escape_text(e.message);
    switch (e.kind) {
      case Kind::Error:
        spdlog::error("Fast DDS [{}] {}", category, message);
        break;
      case Kind::Warning:
        spdlog::warn("Fast DDS [{}] {}", category, message);
        break;
      default:
        spdlog::debug("Fast DDS [{}] {}", category, message);
        break;
    }
  }
};

}  // namespace

void route_fastdds_log_to_spdlog() {
  eprosima::fastdds::dds::Log::ClearConsumers();
  eprosima::fastdds::dds::Log::RegisterConsumer(std::make_unique<SpdlogConsumer>());
}

}  // namespace usvfdi::app
