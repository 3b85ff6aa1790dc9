#include "usv_fdi/io/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <streambuf>
#include <vector>

namespace usvfdi::io {

/// A stream buffer over a file descriptor that keeps the errno of a failed write(2).
class OutputFile::Buffer : public std::streambuf {
 public:
  explicit Buffer(int fd) : fd_(fd), buf_(1 << 16) { setp(buf_.data(), buf_.data() + buf_.size()); }
  /// errno of the first failed write (0: none).
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    if (error_ != 0) return false;
    for (const char* p = pbase(); p < pptr();) {
      const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
      if (n < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return false;
      }
      p += n;
    }
    setp(buf_.data(), buf_.data() + buf_.size());
    return true;
  }

  int fd_;
  std::vector<char> buf_;
  int error_ = 0;
};

namespace {

bool same_stat(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

mode_t new_file_mode() {
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return 0666 & ~mask;
}

}  // namespace

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && same_stat(sa, sb);
}

bool same_file(int fd, const std::string& path) {
  struct stat sa {
  }, sb{};
  return ::fstat(fd, &sa) == 0 && ::stat(path.c_str(), &sb) == 0 && same_stat(sa, sb);
}

void OutputFile::fail(const std::string& what, int error) const {
  throw OutputError(name_ + ": " + what + ": " + std::strerror(error));
}

OutputFile::OutputFile(const std::string& path) : name_(path) {
  if (path.empty() || path == "-") {
    name_ = "stdout";
    fd_ = STDOUT_FILENO;
  } else {
    struct stat st {};
    const bool exists = ::stat(path.c_str(), &st) == 0;
    if (exists && S_ISDIR(st.st_mode)) fail("cannot write", EISDIR);
    if (exists && !S_ISREG(st.st_mode)) {  // a FIFO, a device: no rename onto it
      fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
      if (fd_ < 0) fail("cannot open for writing", errno);
    } else {
      namespace fs = std::filesystem;
      std::error_code ec;
      fs::path target = fs::path(path);
      if (exists) {  // follow symlinks: the link stays, its target is replaced
        const fs::path real = fs::canonical(target, ec);
        if (!ec) target = real;
      }
      const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
      std::string temp = (dir / ("." + target.filename().string() + ".tmp.XXXXXX")).string();
      fd_ = ::mkstemp(temp.data());
      if (fd_ < 0) fail("cannot create a temporary file in " + dir.string(), errno);
      temp_ = temp;
      target_ = target.string();
      ::fcntl(fd_, F_SETFD, FD_CLOEXEC);
      if (::fchmod(fd_, exists ? (st.st_mode & 07777) : new_file_mode()) != 0) {
        const int e = errno;
        ::close(fd_);
        ::unlink(temp_.c_str());
        fail("cannot set the permissions of " + temp_, e);
      }
    }
    owns_fd_ = true;
  }
  buffer_ = std::make_unique<Buffer>(fd_);
  stream_ = std::make_unique<std::ostream>(buffer_.get());
}

OutputFile::~OutputFile() {
  if (owns_fd_ && fd_ >= 0) ::close(fd_);
  if (!temp_.empty()) ::unlink(temp_.c_str());
}

void OutputFile::commit() {
  stream_->flush();
  if (buffer_->error() != 0) fail("write failed", buffer_->error());
  if (!*stream_) fail("write failed", EIO);
  if (target_.empty()) return;
  if (::fsync(fd_) != 0) fail("write failed (fsync)", errno);
  const int closed = ::close(fd_);
  fd_ = -1;
  if (closed != 0) fail("write failed (close)", errno);
  if (::rename(temp_.c_str(), target_.c_str()) != 0) {
    fail("cannot rename " + temp_ + " onto " + target_, errno);
  }
  temp_.clear();
}

}  // namespace usvfdi::io
