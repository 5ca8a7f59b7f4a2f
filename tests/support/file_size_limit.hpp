#pragma once
// A file that cannot grow, standing in for a full disk in tests: while a FileSizeLimit lives, no
// file this process writes grows past `bytes` (RLIMIT_FSIZE, with SIGXFSZ ignored: write(2)
// then takes what fits and refuses the rest with EFBIG, as a full disk says ENOSPC).
#include <signal.h>
#include <sys/resource.h>

namespace sensornet::testing {

class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    previous_ = ::signal(SIGXFSZ, SIG_IGN);
    rlimit limited = saved_;
    limited.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limited);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    ::signal(SIGXFSZ, previous_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  sighandler_t previous_ = SIG_DFL;
};

}  // namespace sensornet::testing
