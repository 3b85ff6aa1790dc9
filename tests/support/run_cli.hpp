// Running the usv-fdi executable from a test: its exit code, stdout and stderr. The including
// test target defines USV_FDI_EXE (the binary) and USV_FDI_SOURCE_DIR (the repository).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace usvfdi::testing_cli {

inline const std::string kExe = USV_FDI_EXE;
inline const std::string kSource = USV_FDI_SOURCE_DIR;

/// What a run left behind: its exit code (-1: killed by a signal), stdout and stderr.
struct Outcome {
  int code = -1;
  std::string out, err;
};

/// The whole file (empty if it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream os;
  os << f.rdbuf();
  return os.str();
}

/// Runs shell commands, their output captured in dir's stdout.txt and stderr.txt (dir ends
/// in '/'); returns the exit code and both outputs.
inline Outcome run_shell(const std::string& commands, const std::string& dir) {
  Outcome r;
  const std::string out = dir + "stdout.txt", err = dir + "stderr.txt";
  const std::string cmd = "{ " + commands + "; } >'" + out + "' 2>'" + err + "'";
  const int status = std::system(cmd.c_str());
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace usvfdi::testing_cli
