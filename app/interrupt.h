// SIGINT and SIGTERM ask a run to stop after its current frame (the frame loop polls); a second
// signal of either kind terminates at once, as without the handler.
#pragma once

namespace crumple::app {

/// Installs the handlers (they only record the signal).
void catch_interrupts();

/// The signal that asked the run to stop, or 0.
int interrupt_signal();

}  // namespace crumple::app
