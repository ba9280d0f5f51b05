#pragma once
/// Long calls from Python that Ctrl-C stops.
///
/// Python runs a signal's handler (KeyboardInterrupt for SIGINT) only on the main thread,
/// holding the GIL, at PyErr_CheckSignals. A call that traces with the GIL released runs its
/// work on a thread of its own and checks for signals from the calling thread every
/// kSignalPoll; when a handler raises, the work is told to stop (it looks between chunks of
/// rays or tiles), the call waits for it and raises what the handler raised. Short calls run
/// on the calling thread, without the extra thread.

#include <atomic>
#include <chrono>
#include <functional>

namespace rp::python {

/// How often a long call looks for signals.
inline constexpr std::chrono::milliseconds kSignalPoll{50};

/// What work throws when it sees `stop` (never seen by Python: the handler's exception is).
struct Stopped {};

/// Runs work(stop) with the GIL released: on its own thread while the caller checks for
/// signals when `long_call`, else on the calling thread (`stop` is then never set). Rethrows
/// what work throws, or raises the signal handler's exception once work has returned.
void interruptible(bool long_call, const std::function<void(const std::atomic<bool>& stop)>& work);

}  // namespace rp::python
