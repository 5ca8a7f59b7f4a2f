#pragma once
// SIGINT and SIGTERM ask an emulator process to stop cleanly: the handler only sets a flag,
// which the process's wait loop (short waitset timeouts) looks at.
//
//   installStopSignals();
//   while (!stopRequested()) { ...; waitset.wait(20ms); }
//   if (launcherDied()) ...  // stopped by the launcher's death, not asked by it

#include <sys/types.h>

#include <csignal>

namespace sensornet::emulator {

// What a child that writes something on the way out (the fusion center) gets when its launcher
// dies (PR_SET_PDEATHSIG). The launcher never sends it otherwise, so the child can tell "my
// launcher died" from "my launcher asks me to stop" (SIGTERM). getppid() cannot tell them
// apart in time: the kernel first hands the children to another thread of the dying launcher,
// whose process id is the launcher's, and sends the signal from there.
inline constexpr int kLauncherDeathSignal = SIGUSR1;

// Handles SIGINT, SIGTERM and kLauncherDeathSignal.
void installStopSignals();
[[nodiscard]] bool stopRequested();
// True when the stop came from kLauncherDeathSignal.
[[nodiscard]] bool launcherDied();

// The launcher's pid when `sensornet launch` started this process (the parent's name is
// sensornet), else 0. Read it at start, while the parent lives: the launcher arms
// kLauncherDeathSignal in it, so that signal (or this parent gone) is the launcher's death.
[[nodiscard]] pid_t launcherParent();

// Ends this process at once with `code`, after flushing the log and standard streams, without
// deleting DDS entities: for when everything owed is written (the report, the episode log) and
// Cyclone would let a reliable writer linger for acknowledgements that readers killed with the
// launcher never send.
[[noreturn]] void leaveNow(int code);

}  // namespace sensornet::emulator
