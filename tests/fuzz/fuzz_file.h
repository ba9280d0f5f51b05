#pragma once
/// What the libFuzzer targets of this folder share: the readers take paths, so each input is
/// written to a scratch file with the extension that selects the format, and the reader is
/// called on that path. rp::Error is the readers' documented answer to bad input and is caught
/// here; anything else (another exception, a crash, a sanitizer report, a hang) escapes to
/// libFuzzer, or to the GoogleTest that replays the corpora (fuzz_corpus_test.cpp), as a finding.
///
/// The scratch folder is per process, on /dev/shm when it is writable (tmpfs: no disk writes
/// at fuzzing speed), else under std::filesystem::temp_directory_path(); it is removed when
/// the process exits normally. A crashing input is in libFuzzer's artifact, not here.

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <system_error>

#include "base/error.h"
#include "core/scene.h"
#include "io/rayfile.h"

namespace rp::fuzz {

/// The folder's path (made on first use). Exits the process when it cannot be made: that is
/// a broken machine, not a finding.
inline const std::filesystem::path& scratch_dir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      namespace fs = std::filesystem;
      const std::string name = "raypack-fuzz-" + std::to_string(::getpid());
      std::error_code ec;
      const fs::path shm = "/dev/shm";
      const fs::path base = ::access(shm.c_str(), W_OK | X_OK) == 0 ? shm : fs::temp_directory_path(ec);
      path = base / name;
      fs::remove_all(path, ec);
      if (!fs::create_directories(path, ec)) {
        std::fprintf(stderr, "fuzz: cannot make the scratch folder %s: %s\n", path.c_str(), ec.message().c_str());
        std::_Exit(2);
      }
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

/// Replaces scratch_dir()/name with `bytes` and returns its path; exits the process on an I/O
/// failure (a full /dev/shm, say), which is not a finding either.
inline std::string write_scratch(std::string_view name, std::span<const uint8_t> bytes) {
  const std::string path = (scratch_dir() / name).string();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  bool ok = fd >= 0;
  for (size_t done = 0; ok && done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n > 0)
      done += size_t(n);
    else if (n < 0 && errno != EINTR)
      ok = false;
  }
  if (fd >= 0 && ::close(fd) != 0) ok = false;
  if (!ok) {
    std::perror(("fuzz: cannot write " + path).c_str());
    std::_Exit(2);
  }
  return path;
}

inline std::string write_scratch(std::string_view name, std::string_view text) {
  return write_scratch(name, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

/// The message of the rp::Error the last run_on_file() caught, empty when its reader returned.
/// Read by the corpus test, which requires the seeds named "valid-*" to load.
inline std::string& last_error() {
  static std::string message;
  return message;
}

/// Writes the input to scratch_dir()/("input" + extension), calls read(path), removes the file
/// (so no input sees an earlier one's file) and returns 0, as LLVMFuzzerTestOneInput must.
template <typename Read>
int run_on_file(const uint8_t* data, size_t size, std::string_view extension, Read&& read) {
  const std::string path = write_scratch("input" + std::string(extension), std::span(data, size));
  last_error().clear();
  try {
    read(path);
  } catch (const Error& e) {
    last_error() = e.what();
    if (last_error().empty()) last_error() = "(an rp::Error with an empty message)";
  }
  ::unlink(path.c_str());
  return 0;
}

/// Where touch() stores its sums: volatile, so the loads and sums cannot be optimised away.
inline volatile float sink_float = 0.0f;
inline volatile size_t sink_count = 0;

/// Uses what a reader returned, so that neither the load nor the reads are optimised away:
/// every mesh vertex, index and material, the analytic shapes and the bounds.
inline void touch(const Scene& scene) {
  float sum = 0.0f;
  size_t count = scene.materials().size() + scene.point_lights().size() + scene.directional_lights().size();
  for (const MeshView& view : scene.meshes()) {
    const TriangleMesh m = to_triangle_mesh(view);
    for (const Vec3f& p : m.positions) sum += p.x + p.y + p.z;
    for (uint32_t i : m.indices) count += i;
    for (uint32_t i : m.face_materials) count += i;
  }
  for (const Vec3f& p : scene.polygon_vertices()) sum += p.x + p.y + p.z;
  count += scene.spheres().size() + scene.quadrics().size() + scene.planes().size() + scene.prim_count() +
           scene.degenerate_triangle_count();
  const Box3f b = scene.bounds();
  if (!b.empty()) sum += b.lo.x + b.hi.z;
  if (scene.camera()) sum += scene.camera()->vfov_degrees;
  sink_float = sum;
  sink_count = count;
}

inline void touch(std::span<const Ray> rays) {
  float sum = 0.0f;
  for (const Ray& r : rays) sum += r.org.x + r.dir.y + r.tnear + r.tfar;
  sink_float = sum;
  sink_count = rays.size();
}

inline void touch(std::span<const HitRecord> hits) {
  float sum = 0.0f;
  uint32_t ids = 0;
  for (const HitRecord& h : hits) {
    sum += h.t + h.u + h.v + h.ng.z;
    ids += h.prim_id;
  }
  sink_float = sum;
  sink_count = ids;
}

}  // namespace rp::fuzz
