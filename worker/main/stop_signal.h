// SIGINT/SIGTERM handling shared by the subcommands: the first signal asks the program to
// stop (polled through stop_requested()); a second one ends the process at once.
#pragma once

namespace keel::worker {

// Installs the handlers (idempotent).
void install_stop_signals();
bool stop_requested();
// The signal that asked to stop (SIGINT, SIGTERM), 0 when none.
int stop_signal();

}  // namespace keel::worker
