// Fast DDS XML QoS profiles: loading and the profile names shipped in
// config/qos/usv_fdi_profiles.xml.
#pragma once

#include <string>

namespace usvfdi::dds {

/// Profile names defined in config/qos/usv_fdi_profiles.xml.
namespace profiles {
// Participants.
inline constexpr const char* kParticipant = "usv_fdi_participant";  // builtin transports (SHM+UDP)
inline constexpr const char* kParticipantLoopback = "usv_fdi_participant_loopback";  // UDPv4 on lo
inline constexpr const char* kParticipantShm = "usv_fdi_participant_shm";  // shared memory only
// INS samples.
inline constexpr const char* kInsWriterBestEffort = "usv_fdi_ins_writer_best_effort";
inline constexpr const char* kInsReaderBestEffort = "usv_fdi_ins_reader_best_effort";
inline constexpr const char* kInsWriterReliable = "usv_fdi_ins_writer_reliable";
inline constexpr const char* kInsReaderReliable = "usv_fdi_ins_reader_reliable";
// Rudder samples.
inline constexpr const char* kRudderWriterBestEffort = "usv_fdi_rudder_writer_best_effort";
inline constexpr const char* kRudderReaderBestEffort = "usv_fdi_rudder_reader_best_effort";
inline constexpr const char* kRudderWriterReliable = "usv_fdi_rudder_writer_reliable";
inline constexpr const char* kRudderReaderReliable = "usv_fdi_rudder_reader_reliable";
// Fault events (latched alarm state; late joiners get the latest state of every instance).
inline constexpr const char* kFaultEventWriter = "usv_fdi_fault_event_writer";
inline constexpr const char* kFaultEventReader = "usv_fdi_fault_event_reader";
// Operator acknowledgements.
inline constexpr const char* kFaultAckWriter = "usv_fdi_fault_ack_writer";
inline constexpr const char* kFaultAckReader = "usv_fdi_fault_ack_reader";
// Per-vessel detector status.
inline constexpr const char* kStatusWriter = "usv_fdi_status_writer";
inline constexpr const char* kStatusReader = "usv_fdi_status_reader";
}  // namespace profiles

/// Makes sure the default profiles (FASTRTPS_DEFAULT_PROFILES_FILE, or
/// DEFAULT_FASTRTPS_PROFILES.xml in the working directory) are loaded, then loads `path` into the
/// process-wide Fast DDS profile registry. A file that was already loaded successfully by this
/// function is not parsed again. Throws std::runtime_error naming the file when Fast DDS rejects it
/// (unreadable, malformed XML, unknown element or bad value, ...). Thread-safe.
///
/// Precedence: profiles loaded first win. The default profiles file is loaded before `path`, so a
/// profile it defines under one of our names overrides ours. Caveat (Fast DDS 2.9): a duplicate
/// profile name or transport id only logs an XMLPARSER error; the load still reports success.
void load_profiles_file(const std::string& path);

/// Loads only the default profiles (see above). Throws std::runtime_error on failure.
void load_default_profiles();

}  // namespace usvfdi::dds
