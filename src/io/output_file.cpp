#include "sensornet/io/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <functional>
#include <ostream>
#include <streambuf>
#include <stdexcept>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;

std::string kindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a regular file";
}

// What is at `path` without following a symbolic link: nullopt if nothing, else its mode.
// Throws std::runtime_error when it cannot be looked at (a folder in the path is missing is
// "nothing": the folder check reports it).
std::optional<mode_t> typeAt(const fs::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) == 0) return info.st_mode;
  if (errno == ENOENT) return std::nullopt;
  throw std::runtime_error(path.string() + ": " + std::strerror(errno));
}

// Closes a file descriptor when the scope ends.
class Descriptor {
 public:
  explicit Descriptor(int fd) noexcept : fd_(fd) {}
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  ~Descriptor() { close(); }
  [[nodiscard]] int get() const noexcept { return fd_; }
  int close() noexcept {
    const int result = fd_ >= 0 ? ::close(fd_) : 0;
    fd_ = -1;
    return result;
  }

 private:
  int fd_;
};

// A fresh, empty temporary file beside `path` (".<name>.XXXXXX"): its descriptor and name.
std::pair<int, fs::path> temporaryBeside(const fs::path& path) {
  std::string name = (path.parent_path() / ("." + path.filename().string() + ".XXXXXX")).string();
  const int fd = ::mkostemp(name.data(), O_CLOEXEC);
  return {fd, fs::path(name)};
}

// 0, or the errno of the write that failed (ENOSPC for one that took nothing: a full disk).
int writeAll(int fd, const char* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    if (n == 0) return ENOSPC;
    done += static_cast<std::size_t>(n);
  }
  return 0;
}

// An output stream buffer over a file descriptor: what is written goes to the file in 64 KiB
// writes; error() is the errno of the first write that failed (0: none), so that the cause told
// is the disk's own, not whatever errno holds by the time the stream is checked.
class DescriptorBuffer : public std::streambuf {
 public:
  explicit DescriptorBuffer(int fd) : fd_(fd), buffer_(1 << 16) {
    setp(buffer_.data(), buffer_.data() + buffer_.size());
  }
  [[nodiscard]] int error() const { return error_; }
  int sync() override {
    const auto size = static_cast<std::size_t>(pptr() - pbase());
    if (size > 0 && error_ == 0) error_ = writeAll(fd_, pbase(), size);
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return error_ != 0 ? -1 : 0;
  }
  int_type overflow(int_type c) override {
    if (sync() != 0) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) sputc(traits_type::to_char_type(c));
    return traits_type::not_eof(c);
  }

 private:
  int fd_;
  std::vector<char> buffer_;
  int error_ = 0;
};

}  // namespace

std::optional<std::string> outputFileProblem(const fs::path& path) {
  if (path.filename().empty()) return "is not a file name";
  struct stat target {};
  if (::lstat(path.c_str(), &target) == 0) {
    if (!S_ISREG(target.st_mode)) return "is " + kindOf(target.st_mode);
  } else if (errno != ENOENT) {
    return std::string("cannot be looked at (") + std::strerror(errno) + ")";
  }
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  struct stat info {};
  if (::stat(folder.c_str(), &info) != 0) {
    return "is in " + folder.string() + ", which does not exist (" + std::strerror(errno) + ")";
  }
  if (!S_ISDIR(info.st_mode)) return "is in " + folder.string() + ", which is not a directory";
  // Create (and remove) a file there: the only test that tells for root, /proc and read-only
  // mounts alike.
  auto [fd, name] = temporaryBeside(path);
  if (fd < 0) {
    return "is in " + folder.string() + ", where no file can be created (" + std::strerror(errno) +
           ")";
  }
  ::close(fd);
  ::unlink(name.c_str());
  return std::nullopt;
}

void checkOutputFile(const fs::path& path, const std::string& option) {
  if (const auto problem = outputFileProblem(path)) {
    throw InputError(option + " " + path.string(), "",
                     "a regular file or a new one in a writable folder; it " + *problem);
  }
}

void replaceFileAtomically(const fs::path& path, const std::string& text,
                           const std::string& what) {
  replaceFileAtomically(path, [&text](std::ostream& out) { out << text; }, what);
}

void replaceFileAtomically(const fs::path& path, const std::function<void(std::ostream&)>& write,
                           const std::string& what) {
  const std::string named = what.empty() ? path.string() : "the " + what + " " + path.string();
  const std::optional<mode_t> existing = typeAt(path);
  if (existing && !S_ISREG(*existing)) {
    throw std::runtime_error("will not replace " + named + ": it is " + kindOf(*existing) +
                             ", not a regular file");
  }
  auto [fd, name] = temporaryBeside(path);
  if (fd < 0) {
    throw std::runtime_error("cannot write " + named + ": " + std::strerror(errno));
  }
  Descriptor file(fd);
  const mode_t mode = existing ? (*existing & 07777) : 0644;
  int error = ::fchmod(file.get(), mode) == 0 ? 0 : errno;
  if (error == 0) {
    DescriptorBuffer buffer(file.get());
    std::ostream out(&buffer);
    write(out);
    out.flush();
    error = buffer.error() != 0 ? buffer.error() : (out ? 0 : EIO);
  }
  if (error == 0 && ::fsync(file.get()) != 0) error = errno;
  if (error == 0 && file.close() != 0) error = errno;
  if (error == 0 && ::rename(name.c_str(), path.c_str()) != 0) error = errno;
  if (error != 0) {
    ::unlink(name.c_str());
    throw std::runtime_error("cannot write " + named + ": " + std::strerror(error));
  }
}

void removeRegularFile(const fs::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode)) ::unlink(path.c_str());
}

}  // namespace sensornet
