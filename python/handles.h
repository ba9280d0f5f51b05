#pragma once
/// raypack.Scene and raypack.Backend as the module holds them, and the scene's lock: what every
/// file that binds calls on them shares (module.cpp, scene.cpp, and the queries).
///
/// Ownership: a Python Scene holds its rp::Scene through a shared_ptr; a Backend is built by
/// make_backend's shared_ptr overload, so it keeps its scene alive on its own, whatever Python
/// does with the Scene object.
///
/// Threads: the GIL is released while tracing, rendering, diffing, changing and updating. Each
/// scene has a reader-writer lock: every call that reads the scene or traces a backend over it
/// holds it shared (reading); the calls that change it (set_vertices, set_transform, the add_*
/// calls, set_mask) and Backend.update hold it alone (changing). So Python threads may change a
/// scene while others trace it: the tracing call finishes on the old state, and then raises
/// raypack.Error until update(). A thread holding the lock alone never waits for the GIL.

#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"

namespace rp::python {

/// raypack.Scene: a scene, the name it is known by in messages and diff summaries (the path it
/// was loaded from, "default", or "arrays"), and its lock (above).
/// The numpy arrays a scene's shared meshes view (Scene.add_triangles(copy=False)), kept alive
/// as long as the scene handle and every Backend over it; released under the GIL from whichever
/// thread lets go last.
struct KeptArrays {
  std::vector<pybind11::object> arrays;
  KeptArrays() = default;
  KeptArrays(const KeptArrays&) = delete;
  KeptArrays& operator=(const KeptArrays&) = delete;
  ~KeptArrays() {
    if (!Py_IsInitialized()) {  // the interpreter is gone: nothing to release them to
      for (pybind11::object& a : arrays) a.release();
      return;
    }
    if (arrays.empty()) return;
    const pybind11::gil_scoped_acquire gil;
    arrays.clear();
  }
};

struct SceneHandle {
  std::shared_ptr<Scene> scene;
  std::string name;
  std::shared_ptr<std::shared_mutex> guard = std::make_shared<std::shared_mutex>();
  std::shared_ptr<KeptArrays> kept = std::make_shared<KeptArrays>();
};

/// The scene's lock held shared: for calls that read the scene.
inline std::shared_lock<std::shared_mutex> reading(const SceneHandle& s) { return std::shared_lock(*s.guard); }

/// The scene's lock held alone, the GIL released: for calls that change the scene.
template <typename F>
auto changing(const SceneHandle& s, const F& change) {
  pybind11::gil_scoped_release release;
  const std::unique_lock writing(*s.guard);
  return change(*s.scene);
}

/// raypack.Backend: a backend and the scene it was built over (which the backend shares too).
struct BackendHandle {
  SceneHandle scene;
  std::unique_ptr<Backend> backend;
};

}  // namespace rp::python
