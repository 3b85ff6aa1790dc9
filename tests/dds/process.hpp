// Minimal child-process helper for the DDS tests: fork/exec with stdout on a pipe, bounded
// waits everywhere, SIGKILL + reap on destruction, and PR_SET_PDEATHSIG so that a child dies
// with the test even when the test process itself is killed: no test leaves a process behind.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace usvfdi::dds::test {

class ChildProcess {
 public:
  /// Spawns argv[0] with the given arguments; stdout is captured. stderr goes to
  /// `stderr_path` (created/truncated) if given, else it is inherited. `extra_env` entries
  /// ("NAME=value") are added to (or override) this process's environment.
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& stderr_path = "",
                        const std::vector<std::string>& extra_env = {});
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const noexcept { return pid_; }

  /// Next stdout line (without '\n'), or nullopt on EOF or when `timeout` elapses.
  std::optional<std::string> read_line(std::chrono::milliseconds timeout);
  /// Everything remaining on stdout until EOF or `timeout`.
  std::string read_all(std::chrono::milliseconds timeout);

  /// True while the child has not exited (reaps it if it has).
  bool running();
  /// Sends `sig` to the child if it is still running.
  void signal(int sig);
  /// Waits up to `timeout` for the child to exit. Returns its exit code, 128+signal if it was
  /// killed by a signal, or nullopt if it is still running.
  std::optional<int> wait_exit(std::chrono::milliseconds timeout);

 private:
  bool fill(std::chrono::steady_clock::time_point deadline);

  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool eof_ = false;
  std::string buffer_;
  std::optional<int> exit_code_;
};

}  // namespace usvfdi::dds::test
