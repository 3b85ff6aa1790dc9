#include "usv_fdi/dds/profiles.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

#include <fastrtps/types/TypesBase.h>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>

namespace usvfdi::dds {
namespace {

using eprosima::fastdds::dds::DomainParticipantFactory;
using eprosima::fastrtps::types::ReturnCode_t;

std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}

// Files this process has loaded successfully. (Fast DDS 2.9 itself skips a path it has already
// parsed; keeping our own record makes the idempotence explicit and version independent.)
std::set<std::string>& loaded_files() {
  static std::set<std::string> files;
  return files;
}

DomainParticipantFactory& factory() {
  DomainParticipantFactory* f = DomainParticipantFactory::get_instance();
  if (f == nullptr) {
    throw std::runtime_error("usvfdi::dds: DomainParticipantFactory::get_instance() returned null");
  }
  return *f;
}

void load_default_profiles_locked() {
  // Loads FASTRTPS_DEFAULT_PROFILES_FILE (or ./DEFAULT_FASTRTPS_PROFILES.xml) once per process.
  if (factory().load_profiles() != ReturnCode_t::RETCODE_OK) {
    throw std::runtime_error(
        "usvfdi::dds: loading the default Fast DDS profiles failed "
        "(FASTRTPS_DEFAULT_PROFILES_FILE / DEFAULT_FASTRTPS_PROFILES.xml)");
  }
}

}  // namespace

void load_default_profiles() {
  std::lock_guard<std::mutex> lock(registry_mutex());
  load_default_profiles_locked();
}

void load_profiles_file(const std::string& path) {
  if (path.empty()) {
    throw std::invalid_argument("usvfdi::dds: empty XML profiles file path");
  }
  std::lock_guard<std::mutex> lock(registry_mutex());
  load_default_profiles_locked();
  if (loaded_files().count(path) != 0) return;
  // Fast DDS only logs that it could not open the file; name the system's reason first.
  int err = 0;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0) {
    err = errno;
  } else if (S_ISDIR(st.st_mode)) {
    err = EISDIR;
  }
  if (fd >= 0) ::close(fd);
  if (err != 0) {
    throw std::runtime_error("usvfdi::dds: cannot read the XML profiles file '" + path +
                             "': " + std::strerror(err));
  }
  if (factory().load_XML_profiles_file(path) != ReturnCode_t::RETCODE_OK) {
    throw std::runtime_error("usvfdi::dds: Fast DDS rejected the XML profiles file '" + path +
                             "' (malformed or duplicate profile names; see the Fast DDS error "
                             "log)");
  }
  loaded_files().insert(path);
}

}  // namespace usvfdi::dds
