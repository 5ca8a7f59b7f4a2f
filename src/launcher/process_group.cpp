#include "sensornet/launcher/process_group.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <deque>
#include <fstream>
#include <initializer_list>
#include <stdexcept>
#include <thread>
#include <utility>

namespace sensornet::launcher {
namespace {

constexpr std::chrono::milliseconds kPollInterval{20};

// Closes a file descriptor when the scope ends.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) noexcept : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int get() const noexcept { return fd_; }

 private:
  int fd_;
};

// Sends `signal` to the child's process group (it leads one), or to the child alone if the
// group is already gone.
void signalChild(pid_t pid, int signal) {
  if (::kill(-pid, signal) != 0) (void)::kill(pid, signal);
}

// Runs in the forked child, where only async-signal-safe calls are allowed: everything it needs
// was prepared by the parent.
[[noreturn]] void becomeChild(pid_t parent, int death_signal, int log_fd, int null_fd, int max_fd,
                              char* const* argv, const std::string& exec_failure) {
  ::setpgid(0, 0);
  // Default dispositions first: the launcher's handlers would swallow the death signal.
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  sigemptyset(&default_action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGPIPE, SIGCHLD, SIGHUP, SIGUSR1}) {
    ::sigaction(signal, &default_action, nullptr);
  }
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  // Dies with the launcher. If the launcher died before this line, the signal was never
  // armed: leave now instead of running orphaned.
  ::prctl(PR_SET_PDEATHSIG, death_signal);
  if (::getppid() != parent) ::_exit(127);
  ::dup2(null_fd, STDIN_FILENO);
  ::dup2(log_fd, STDOUT_FILENO);
  ::dup2(log_fd, STDERR_FILENO);
  // Nothing else of the launcher's goes along: Cyclone's sockets are not close-on-exec, and a
  // child holding the launcher's DDS ports would keep them bound after the launcher is gone.
  if (::close_range(STDERR_FILENO + 1, ~0U, 0) != 0) {
    for (int fd = STDERR_FILENO + 1; fd < max_fd; ++fd) ::close(fd);
  }
  ::execv(argv[0], argv);
  (void)!::write(STDERR_FILENO, exec_failure.data(), exec_failure.size());
  ::_exit(127);
}

}  // namespace

ProcessGroup::~ProcessGroup() { (void)stopAll(std::chrono::seconds(3)); }

pid_t ProcessGroup::start(const ChildSpec& spec) {
  if (spec.argv.empty()) throw std::runtime_error("no program given for " + spec.name);
  FileDescriptor log(::open(spec.log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (log.get() < 0) {
    throw std::runtime_error("cannot open log file " + spec.log_path.string() + ": " +
                             std::strerror(errno));
  }
  FileDescriptor null_input(::open("/dev/null", O_RDONLY | O_CLOEXEC));
  std::vector<char*> argv;
  for (const std::string& arg : spec.argv) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  const std::string exec_failure = "sensornet: cannot execute " + spec.argv.front() + "\n";

  const int max_fd = static_cast<int>(::sysconf(_SC_OPEN_MAX));
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("cannot start " + spec.name + ": fork failed");
  if (pid == 0) {
    becomeChild(parent, spec.parent_death_signal, log.get(), null_input.get(), max_fd, argv.data(),
                exec_failure);
  }
  ::setpgid(pid, pid);  // also in the parent, so that a signal sent right now reaches the group
  children_.push_back({spec, pid, true});
  return pid;
}

void ProcessGroup::collect(pid_t pid, int status) {
  for (Child& child : children_) {
    if (child.pid != pid || !child.running) continue;
    child.running = false;
    ChildExit exit{child.spec.name, pid, 0, 0};
    if (WIFSIGNALED(status)) {
      exit.signal = WTERMSIG(status);
      exit.exit_code = 128 + exit.signal;
    } else {
      exit.exit_code = WEXITSTATUS(status);
    }
    pending_.push_back(exit);
  }
}

std::vector<ChildExit> ProcessGroup::reap() {
  for (const Child& child : children_) {
    if (!child.running) continue;
    int status = 0;
    if (::waitpid(child.pid, &status, WNOHANG) == child.pid) collect(child.pid, status);
  }
  return std::exchange(pending_, {});
}

std::optional<ChildExit> ProcessGroup::waitFor(const std::string& name,
                                               std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  for (;;) {
    std::vector<ChildExit> ended = reap();
    std::optional<ChildExit> found;
    for (ChildExit& e : ended) {
      if (e.name == name) {
        found = e;
      } else {
        pending_.push_back(e);
      }
    }
    if (found) return found;
    if (!isRunning(name) || std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(kPollInterval);
  }
}

bool ProcessGroup::isRunning(const std::string& name) const {
  return std::any_of(children_.begin(), children_.end(),
                     [&](const Child& c) { return c.running && c.spec.name == name; });
}

std::vector<std::string> ProcessGroup::runningNames() const {
  std::vector<std::string> names;
  for (const Child& child : children_) {
    if (child.running) names.push_back(child.spec.name);
  }
  return names;
}

std::vector<pid_t> ProcessGroup::runningPids() const {
  std::vector<pid_t> pids;
  for (const Child& child : children_) {
    if (child.running) pids.push_back(child.pid);
  }
  return pids;
}

std::optional<std::filesystem::path> ProcessGroup::logOf(const std::string& name) const {
  // The latest child of that name: a restarted process logs to a file of its own.
  for (auto child = children_.rbegin(); child != children_.rend(); ++child) {
    if (child->spec.name == name) return child->spec.log_path;
  }
  return std::nullopt;
}

std::vector<ChildExit> ProcessGroup::stopAll(std::chrono::milliseconds grace) {
  std::vector<ChildExit> ended = stop(runningNames(), grace);
  for (ChildExit& e : reap()) ended.push_back(e);
  return ended;
}

bool ProcessGroup::anyRunning(const std::vector<std::string>& names) const {
  return std::any_of(names.begin(), names.end(),
                     [&](const std::string& name) { return isRunning(name); });
}

std::vector<ChildExit> ProcessGroup::stop(const std::vector<std::string>& names,
                                          std::chrono::milliseconds grace) {
  const auto named = [&](const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  for (const Child& child : children_) {
    if (child.running && named(child.spec.name)) signalChild(child.pid, SIGTERM);
  }
  const auto deadline = std::chrono::steady_clock::now() + grace;
  std::vector<ChildExit> ended;
  std::vector<ChildExit> others;
  const auto sort = [&](std::vector<ChildExit> exits) {
    for (ChildExit& e : exits) (named(e.name) ? ended : others).push_back(std::move(e));
  };
  for (;;) {
    sort(reap());
    if (!anyRunning(names) || std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(kPollInterval);
  }
  for (const Child& child : children_) {
    if (!child.running || !named(child.spec.name)) continue;
    signalChild(child.pid, SIGKILL);
    int status = 0;
    if (::waitpid(child.pid, &status, 0) == child.pid) collect(child.pid, status);
  }
  sort(reap());
  pending_.insert(pending_.end(), others.begin(), others.end());
  return ended;
}

std::optional<std::string> lastErrorLine(const std::filesystem::path& path) {
  constexpr std::string_view kMark = ": error: ";
  std::ifstream in(path);
  std::optional<std::string> last;
  for (std::string line; std::getline(in, line);) {
    if (const std::size_t at = line.find(kMark); at != std::string::npos) {
      last = line.substr(at + kMark.size());
    }
  }
  return last;
}

std::string lastLines(const std::filesystem::path& path, std::size_t count) {
  std::ifstream in(path);
  std::deque<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(line);
    if (lines.size() > count) lines.pop_front();
  }
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

}  // namespace sensornet::launcher
