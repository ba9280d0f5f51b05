#include "python/interrupt.h"

#include <pybind11/pybind11.h>

#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace rp::python {

namespace py = pybind11;

void interruptible(bool long_call, const std::function<void(const std::atomic<bool>& stop)>& work) {
  std::atomic<bool> stop{false};
  if (!long_call) {
    py::gil_scoped_release release;
    work(stop);
    return;
  }
  std::exception_ptr failure;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    std::thread worker([&] {
      try {
        work(stop);
      } catch (...) {
        failure = std::current_exception();
      }
      const std::lock_guard lock(m);
      done = true;
      cv.notify_one();
    });
    std::unique_lock lock(m);
    while (!cv.wait_for(lock, kSignalPoll, [&] { return done; })) {
      if (interrupted) continue;
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        // The error the handler raised stays set on this thread while the work winds down.
        if (PyErr_CheckSignals() != 0) {
          interrupted = true;
          stop = true;
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (interrupted) throw py::error_already_set();
  if (failure) {
    try {
      std::rethrow_exception(failure);
    } catch (const Stopped&) {
      return;  // unreachable: stop is only set when interrupted
    }
  }
}

}  // namespace rp::python
