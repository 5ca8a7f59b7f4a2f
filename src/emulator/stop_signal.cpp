#include "sensornet/emulator/stop_signal.hpp"

#include <initializer_list>

namespace sensornet::emulator {
namespace {

volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_launcher_died = 0;

extern "C" void onStopSignal(int signal) {
  if (signal == kLauncherDeathSignal) g_launcher_died = 1;
  g_stop = 1;
}

}  // namespace

void installStopSignals() {
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGINT, SIGTERM, kLauncherDeathSignal}) sigaction(signal, &action, nullptr);
}

bool stopRequested() { return g_stop != 0; }

bool launcherDied() { return g_launcher_died != 0; }

}  // namespace sensornet::emulator
