#include "interrupt.h"

#include <csignal>

namespace crumple::app {

namespace {

volatile std::sig_atomic_t g_signal = 0;

void record(int signal) { g_signal = signal; }

}  // namespace

void catch_interrupts() {
  struct sigaction action {};
  action.sa_handler = record;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: the next signal gets the default action (terminate); SA_RESTART: writes in
  // progress are not cut by EINTR.
  action.sa_flags = SA_RESETHAND | SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int interrupt_signal() { return g_signal; }

}  // namespace crumple::app
