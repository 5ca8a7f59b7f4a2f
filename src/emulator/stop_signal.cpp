#include "sensornet/emulator/stop_signal.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>

#include <fstream>
#include <initializer_list>
#include <string>

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

pid_t launcherParent() {
  const pid_t parent = ::getppid();
  std::ifstream comm("/proc/" + std::to_string(parent) + "/comm");
  std::string name;
  std::getline(comm, name);
  return name == "sensornet" ? parent : 0;
}

void leaveNow(int code) {
  spdlog::shutdown();
  std::fflush(nullptr);
  ::_exit(code);
}

}  // namespace sensornet::emulator
