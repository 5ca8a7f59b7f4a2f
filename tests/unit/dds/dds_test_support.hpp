#pragma once
// Shared by the DDS tests: per-test isolation (a domain id and partition of its own, so tests
// can run in parallel processes), waiting for samples with a deadline, and child processes that
// play the other side of a cross-process test.
//
// A child is this same test executable running one DISABLED_ test of the fixture DdsChild,
// selected by --gtest_filter; the parent passes the domain and partition in the environment and
// the child says "ready" on a pipe. ChildProcess kills (SIGKILL) and reaps its child on
// destruction, so no process outlives its test.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/waitset.hpp"

extern char** environ;

namespace sensornet::dds::testing {

using namespace std::chrono_literals;

inline constexpr const char* kChildDomainVariable = "SENSORNET_DDS_TEST_DOMAIN";
inline constexpr const char* kChildPartitionVariable = "SENSORNET_DDS_TEST_PARTITION";
inline constexpr const char* kChildReadyFdVariable = "SENSORNET_DDS_TEST_READY_FD";
inline constexpr int kChildReadyFd = 3;

inline std::string currentTestName() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return std::string(info->test_suite_name()) + "." + info->name();
}

// Loopback configuration on a domain id and partition unique to this test in this process.
inline DomainConfig isolatedDomain() {
  const std::string name = currentTestName() + "." + std::to_string(::getpid());
  std::string partition = "test/" + name;
  return DomainConfig::loopback(domainIdForRun(name), partition);
}

// Takes from `reader` until `count` valid samples arrived or `timeout` passed; instance changes
// seen on the way are kept in the batch too.
template <class T>
Batch<T> takeAtLeast(const Participant& participant, Reader<T>& reader, std::size_t count,
                     std::chrono::nanoseconds timeout) {
  Batch<T> all;
  ReadCondition has_data(reader);
  WaitSet waitset(participant);
  waitset.attach(has_data, 1);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (all.samples.size() < count) {
    Batch<T> batch = reader.take(1024);
    for (auto& s : batch.samples) all.samples.push_back(std::move(s));
    for (auto& c : batch.changes) all.changes.push_back(std::move(c));
    if (all.samples.size() >= count) break;
    const auto remaining = deadline - std::chrono::steady_clock::now();
    if (remaining <= 0ns) break;
    (void)waitset.wait(std::min<std::chrono::nanoseconds>(remaining, 100ms));
  }
  return all;
}

// Takes from `reader` until an instance change with `state` arrives or `timeout` passes.
template <class T, class KeyMatches>
bool waitForInstanceState(const Participant& participant, Reader<T>& reader, InstanceState state,
                          KeyMatches key_matches, std::chrono::nanoseconds timeout) {
  ReadCondition has_data(reader);
  WaitSet waitset(participant);
  waitset.attach(has_data, 1);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    for (const auto& change : reader.take(1024).changes) {
      if (change.info.instance_state == state && key_matches(*change.key)) return true;
    }
    const auto remaining = deadline - std::chrono::steady_clock::now();
    if (remaining <= 0ns) return false;
    (void)waitset.wait(std::min<std::chrono::nanoseconds>(remaining, 100ms));
  }
}

// The parent's side of a cross-process test.
class ChildProcess {
 public:
  // Starts DdsChild.DISABLED_<role> of this executable on `config`'s domain and partition.
  ChildProcess(const std::string& role, const DomainConfig& config) {
    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
    ready_fd_ = pipe_fds[0];

    std::vector<std::string> args = {"/proc/self/exe", "--gtest_filter=DdsChild.DISABLED_" + role,
                                     "--gtest_also_run_disabled_tests"};
    std::vector<std::string> env;
    for (char** e = environ; *e != nullptr; ++e) env.emplace_back(*e);
    env.push_back(std::string(kChildDomainVariable) + "=" + std::to_string(config.domain_id));
    env.push_back(std::string(kChildPartitionVariable) + "=" + config.partition);
    env.push_back(std::string(kChildReadyFdVariable) + "=" + std::to_string(kChildReadyFd));

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], kChildReadyFd);  // clears CLOEXEC
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    const int result = ::posix_spawn(&pid_, "/proc/self/exe", &actions, nullptr,
                                     pointers(args).data(), pointers(env).data());
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_fds[1]);
    if (result != 0) throw std::runtime_error("posix_spawn failed");
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(ready_fd_);
  }

  // True once the child wrote its ready line; false on timeout or if it died first.
  bool waitReady(std::chrono::milliseconds timeout) {
    pollfd fd{ready_fd_, POLLIN, 0};
    if (::poll(&fd, 1, static_cast<int>(timeout.count())) != 1) return false;
    char c = 0;
    return ::read(ready_fd_, &c, 1) == 1;
  }

  void kill(int signal) { ::kill(pid_, signal); }

  // The exit code once the child ended (128 + signal if killed), or -1 if still running at
  // the deadline.
  int waitExit(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = 0;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (std::chrono::steady_clock::now() > deadline) return -1;
      std::this_thread::sleep_for(10ms);
    }
  }

 private:
  static std::vector<char*> pointers(std::vector<std::string>& strings) {
    std::vector<char*> out;
    for (auto& s : strings) out.push_back(s.data());
    out.push_back(nullptr);
    return out;
  }

  pid_t pid_ = 0;
  int ready_fd_ = -1;
};

// The child's side: true when this process runs as a child (else the DdsChild test skips).
inline bool runningAsChild() { return std::getenv(kChildDomainVariable) != nullptr; }

inline DomainConfig childDomain() {
  return DomainConfig::loopback(parseDomainId(std::getenv(kChildDomainVariable), "test parent"),
                                std::getenv(kChildPartitionVariable));
}

inline void tellParentReady() {
  const char c = 'R';
  if (::write(kChildReadyFd, &c, 1) != 1) std::abort();
}

}  // namespace sensornet::dds::testing
