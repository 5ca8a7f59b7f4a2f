#include "support/background_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "support/sanitizer.hpp"

extern char** environ;

namespace sensornet::testing {
namespace {

int decode(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace

BackgroundProcess::BackgroundProcess(const std::vector<std::string>& argv,
                                     const std::string& log_path)
    : log_path_(log_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(),
                                   O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int rc = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
}

BackgroundProcess::BackgroundProcess(BackgroundProcess&& other) noexcept
    : pid_(other.pid_), status_(other.status_), log_path_(std::move(other.log_path_)) {
  other.pid_ = -1;
}

BackgroundProcess::~BackgroundProcess() {
  if (pid_ > 0 && !status_) (void)stop();
}

std::optional<int> BackgroundProcess::waitForExit(std::chrono::milliseconds timeout) {
  if (status_ || pid_ <= 0) return status_;
  const auto deadline = std::chrono::steady_clock::now() + scaledLimit(timeout);
  for (;;) {
    int status = 0;
    const pid_t done = ::waitpid(pid_, &status, WNOHANG);
    if (done == pid_) {
      status_ = decode(status);
      return status_;
    }
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

int BackgroundProcess::stop(std::chrono::milliseconds grace) {
  if (status_ || pid_ <= 0) return status_.value_or(-1);
  ::kill(pid_, SIGTERM);
  if (auto code = waitForExit(grace)) return *code;
  ::kill(pid_, SIGKILL);
  return waitForExit(std::chrono::milliseconds(10000)).value_or(-1);
}

std::string BackgroundProcess::log() const {
  std::ifstream in(log_path_);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

bool processExists(pid_t pid) {
  if (::kill(pid, 0) != 0) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  const auto close = line.rfind(')');
  return close == std::string::npos || line.size() < close + 3 || line[close + 2] != 'Z';
}

std::vector<pid_t> processesMentioning(const std::string& token) {
  // A short token matches processes that are not the test's: LeftoverGuard would kill them.
  if (token.size() < kMinProcessToken) {
    throw std::invalid_argument("processesMentioning: a token of at least " +
                                std::to_string(kMinProcessToken) + " characters, got '" + token +
                                "'");
  }
  std::vector<pid_t> found;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = std::stoi(name);
    if (pid == ::getpid()) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::ostringstream text;
    text << in.rdbuf();
    std::string cmdline = text.str();
    for (char& c : cmdline) c = c == '\0' ? ' ' : c;
    if (cmdline.find(token) != std::string::npos) found.push_back(pid);
  }
  return found;
}

LeftoverGuard::LeftoverGuard(std::string token) : token_(std::move(token)) {
  (void)processesMentioning(token_);  // refuses a token that would match other processes
}

LeftoverGuard::~LeftoverGuard() {
  for (const pid_t pid : processesMentioning(token_)) ::kill(pid, SIGKILL);
}

}  // namespace sensornet::testing
