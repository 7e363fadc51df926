// SIGINT/SIGTERM handling shared by the subcommands: the first signal asks the program to
// stop (polled through stop_requested()); a second one, 2 s or more later, ends the process at
// once (sooner it is the same stop delivered twice, as Slurm and a batch shell both do).
#pragma once

namespace keel::worker {

// Installs the handlers (idempotent).
void install_stop_signals();
bool stop_requested();
// The signal that asked to stop (SIGINT, SIGTERM), 0 when none.
int stop_signal();

}  // namespace keel::worker
