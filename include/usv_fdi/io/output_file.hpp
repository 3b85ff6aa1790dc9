// Output files that a failed run cannot damage.
//
// OutputFile writes a regular file through a temporary file in the same directory
// (".<name>.tmp.XXXXXX", created with the target's permissions, or 0666 & ~umask for a new
// file) and renames it onto the target in commit(), after fsync: until then an existing
// file keeps its old content, and a run that fails (an error, a full disk, a signal before
// commit) leaves it untouched. A symlink is followed (the link stays, its target is
// replaced). Standard output ("-" or "") and targets that are not regular files (a FIFO,
// /dev/null, a terminal) are written directly. Every failure names the file and the
// operating system's reason (strerror).
#pragma once

#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>

namespace usvfdi::io {

/// An output file that cannot be created or written: "<file>: <what>: <strerror>".
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// True when both paths name one existing file (the same device and inode, so also through
/// a symlink, a hard link or a different spelling of the path); false when either is absent.
bool same_file(const std::string& a, const std::string& b);
/// True when the open descriptor `fd` is the existing file at `path`.
bool same_file(int fd, const std::string& path);

class OutputFile {
 public:
  /// Opens `path` for writing ("-" or "": standard output). Throws OutputError.
  explicit OutputFile(const std::string& path);
  /// Without commit(): removes the temporary file; the target is unchanged.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream() { return *stream_; }
  /// Flushes; for a regular file also fsyncs and renames the temporary file onto the
  /// target. Throws OutputError (then the target is unchanged).
  void commit();

  /// The path as given, or "stdout".
  const std::string& name() const { return name_; }
  /// The descriptor written to (1 for standard output).
  int fd() const { return fd_; }

 private:
  class Buffer;
  [[noreturn]] void fail(const std::string& what, int error) const;

  std::string name_;
  std::string target_;  ///< the file renamed onto (symlinks resolved); empty: direct
  std::string temp_;    ///< the temporary file; empty once renamed or when direct
  int fd_ = -1;
  bool owns_fd_ = false;
  std::unique_ptr<Buffer> buffer_;
  std::unique_ptr<std::ostream> stream_;
};

}  // namespace usvfdi::io
