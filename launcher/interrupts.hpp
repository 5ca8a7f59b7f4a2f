#pragma once
// Ctrl-C (SIGINT), SIGTERM and SIGHUP ask the launcher to stop the run: the handler only
// records which signal came, and the launcher's watch loop (short waits) looks at it, stops
// every child and exits (130 after Ctrl-C, 1 otherwise).
//
//   installInterruptHandlers();
//   while (...) { if (const int signal = pendingInterrupt()) return stop(signal); ... }

namespace sensornet::launcher {

void installInterruptHandlers();
// The first interrupting signal received, 0 if none.
[[nodiscard]] int pendingInterrupt();

}  // namespace sensornet::launcher
