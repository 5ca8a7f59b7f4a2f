#pragma once
// SIGINT and SIGTERM ask an emulator process to stop cleanly: the handler only sets a flag,
// which the process's wait loop (short waitset timeouts) looks at.
//
//   installStopSignals();
//   while (!stopRequested()) { ...; waitset.wait(20ms); }

namespace sensornet::emulator {

void installStopSignals();
[[nodiscard]] bool stopRequested();

}  // namespace sensornet::emulator
