#include "interrupts.hpp"

#include <csignal>
#include <initializer_list>

namespace sensornet::launcher {
namespace {

// Written only by the signal handler; a signal handler can share nothing else safely.
volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void onInterrupt(int signal) {
  if (g_interrupt == 0) g_interrupt = signal;
}

}  // namespace

void installInterruptHandlers() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
}

int pendingInterrupt() { return g_interrupt; }

}  // namespace sensornet::launcher
