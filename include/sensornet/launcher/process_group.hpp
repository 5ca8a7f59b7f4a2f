#pragma once
// The child processes of one launched emulation: started with their output in a log file each,
// tied to the launcher's life (PR_SET_PDEATHSIG, ChildSpec::parent_death_signal: a launcher that
// dies, even by SIGKILL, takes them with it), watched without blocking, and stopped together
// (SIGTERM, then SIGKILL after a grace period). The destructor stops whatever is still running,
// so no path leaves a process behind.
//
//   ProcessGroup group;
//   group.start({"coordinator", {"/usr/bin/coordinator", "serve", ...}, "run/coordinator.log"});
//   for (const ChildExit& e : group.reap()) ...;  // children that ended since the last call
//   group.stopAll(std::chrono::seconds(3));       // SIGTERM, wait, SIGKILL
//
// Children run in their own process group, so a Ctrl-C at the terminal reaches only the
// launcher, which then stops them in order. Start children from the thread that lives as long
// as the launcher (the main thread): the death signal fires when the creating thread exits.

#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/launcher/launch_plan.hpp"  // ChildSpec
#include "sensornet/launcher/supervisor.hpp"  // ChildExit

namespace sensornet::launcher {

class ProcessGroup {
 public:
  ProcessGroup() = default;
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;
  // Stops every child still running (SIGTERM, then SIGKILL after 3 s) and reaps it.
  ~ProcessGroup();

  // Starts a child; returns its pid. Throws std::runtime_error when the log file cannot be
  // opened or the program cannot be started (exec failure is reported by the child as exit
  // status 127 with a line in its log).
  pid_t start(const ChildSpec& spec);

  // Collects the children that ended since the last call, without blocking.
  [[nodiscard]] std::vector<ChildExit> reap();
  // Waits up to `limit` for the named child to end; its exit, or nullopt if it still runs.
  // Other children that end meanwhile are collected and returned by the next reap().
  [[nodiscard]] std::optional<ChildExit> waitFor(const std::string& name,
                                                 std::chrono::milliseconds limit);

  [[nodiscard]] bool isRunning(const std::string& name) const;
  [[nodiscard]] std::vector<std::string> runningNames() const;
  [[nodiscard]] std::vector<pid_t> runningPids() const;
  // The log of the latest child started under `name`.
  [[nodiscard]] std::optional<std::filesystem::path> logOf(const std::string& name) const;

  // SIGTERM to every running child, SIGKILL to those still running after `grace`, and reaps
  // them all. Returns how each ended (also those that ended earlier and were not reaped yet).
  // Safe to call when nothing runs.
  std::vector<ChildExit> stopAll(std::chrono::milliseconds grace);
  // The same for the named children only; others that end meanwhile are left for reap().
  std::vector<ChildExit> stop(const std::vector<std::string>& names,
                              std::chrono::milliseconds grace);

 private:
  struct Child {
    ChildSpec spec;
    pid_t pid = 0;
    bool running = true;
  };
  // Reaps one pid if it ended (non-blocking); records its exit in pending_.
  void collect(pid_t pid, int status);
  [[nodiscard]] bool anyRunning(const std::vector<std::string>& names) const;
  std::vector<Child> children_;
  std::vector<ChildExit> pending_;  // ended, not yet returned by reap()
};

// The last `count` lines of a text file ("" when it cannot be read).
[[nodiscard]] std::string lastLines(const std::filesystem::path& path, std::size_t count);
// What a program of ours said last on failing: the text after "error: " of the last line of its
// log that holds one ("cannot write ...: No space left on device"); nullopt when none does.
[[nodiscard]] std::optional<std::string> lastErrorLine(const std::filesystem::path& path);

}  // namespace sensornet::launcher
