#include "sensornet/launcher/run_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "sensornet/core/input_error.hpp"

namespace sensornet::launcher {
namespace {

// The pid the holder wrote into the lock file, or "" if unreadable.
std::string holderOf(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  if (n <= 0) return "";
  std::string pid(text, static_cast<std::size_t>(n));
  while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
  return pid;
}

}  // namespace

RunLock::RunLock(const std::filesystem::path& log_dir, const std::string& run_id)
    : path_(log_dir / "launch.lock") {
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0600);
  struct stat info {};
  if (fd_ < 0 || ::fstat(fd_, &info) != 0 || !S_ISREG(info.st_mode)) {
    const std::string reason = fd_ < 0 ? std::strerror(errno) : "not a regular file";
    if (fd_ >= 0) ::close(fd_);
    throw std::runtime_error("cannot use the lock file " + path_.string() + ": " + reason);
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    const std::string holder = holderOf(fd_);
    ::close(fd_);
    if (error == EWOULDBLOCK) {
      throw InputError("--run-id " + run_id, "",
                       "a run id not in use on this host: run " + run_id +
                           " is already going on (launcher pid " +
                           (holder.empty() ? std::string("unknown") : holder) + " holds " +
                           path_.string() + ")");
    }
    throw std::runtime_error("cannot lock " + path_.string() + ": " + std::strerror(error));
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
    // The lock holds anyway; only the pid shown to a refused launch is missing.
  }
}

RunLock::~RunLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

}  // namespace sensornet::launcher
