#pragma once
/// Ranks that read different files under one path: a node with a stale copy of the scene, a
/// shorter ray file. Each rank loads its own copy, so without a check the run mixes two
/// inputs and exits 0 (a checkerboard of two scenes, hits that do not add up).
///
/// Before any work, every rank's digest of each input is compared with rank 0's; a rank whose
/// digest differs fails the run on every rank, naming itself, the flag and the path. What a
/// digest covers:
/// - a scene: everything loaded that a trace or render reads (meshes with their names,
///   vertices, indices, normals, uvs and materials; spheres, quadrics, polygons, planes,
///   instances, materials, lights, camera, up axis) and its animation (every curve's
///   keyframes, the nodes it moves and what they place), hashed with XXH3 (xxHash): any change
///   in what is loaded, from the scene file or a file it names (a material library, a mesh, a
///   glTF buffer), changes the digest;
/// - a file read in parts (a ray file, each rank reading its share): its size and XXH3 of its
///   first and last 64 KiB and of 62 blocks of 64 KiB evenly spaced between them (at most 4 MiB
///   read per rank, whatever the file's size): a copy of another length or of other rays
///   differs, while two copies that differ only between the sampled blocks are not caught.

#include <cstdint>
#include <string>
#include <vector>

#include "core/scene.h"
#include "io/loaders/animation.h"
#include "mpi/comm.h"

namespace rp::dist {

/// XXH3 (64-bit) of what a trace or render reads of `scene` (see the top of this file).
uint64_t scene_digest(const Scene& scene);

/// The same of `scene` and the animation that poses it (a render of several frames reads
/// every pose).
uint64_t scene_digest(const Scene& scene, const SceneAnimation& animation);

/// The size and sampled XXH3 of the regular file `path` (see the top of this file). Throws
/// rp::Error naming the path when it cannot be read.
uint64_t file_digest(const std::string& path);

/// One input of a command: the flag and path that named it, and this rank's digest of it.
struct InputDigest {
  std::string flag, path;
  uint64_t digest = 0;
};

/// Collective: throws on every rank (RankFailure, as together() does) when a rank's digest of
/// an input differs from rank 0's: "rank N: <flag> <path>: not what rank 0 read (another file
/// under the same path on this rank's node?)". Nothing to check with one process.
void check_same_inputs(const Comm& comm, const std::vector<InputDigest>& inputs);

}  // namespace rp::dist
