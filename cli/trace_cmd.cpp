#include "cli/trace_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>

#include "analysis/raygen.h"
#include "base/text.h"
#include "cli/args.h"
#include "cli/out_of_memory.h"
#include "core/invalid_rays.h"
#include "io/rayfile.h"
#include "mpi/ray_parts.h"
#include "mpi/same_inputs.h"

namespace rp::cli {

namespace {

/// What --query asks of each ray.
enum class Query { closest, occluded, count, all };

Query parse_query(const std::string& text) {
  if (text == "closest") return Query::closest;
  if (text == "occluded") return Query::occluded;
  if (text == "count") return Query::count;
  if (text == "all") return Query::all;
  throw UsageError(cat("--query: '", text, "' is not closest, occluded, count or all"));
}

/// The hit record (with its geometric normal) of hit `h` of ray `r`, for a hit file.
HitRecord record_of(const Scene& scene, const Ray& r, const Hit& h) {
  return {h.t, h.prim_id, h.u, h.v, scene.surface(r, h).geometric_normal, h.instance_id};
}

/// Hit records (with geometric normals) for writing to a hit file.
std::vector<HitRecord> to_records(const Scene& scene, std::span<const Ray> rays, std::span<const Hit> hits) {
  std::vector<HitRecord> out(hits.size());
  for (size_t i = 0; i < hits.size(); ++i)
    if (hits[i].hit()) out[i] = record_of(scene, rays[i], hits[i]);
  return out;
}

/// The answers of a query other than the closest hit (one of the three, by the query).
struct Answers {
  std::vector<uint8_t> occluded;
  std::vector<uint32_t> counts;
  HitList all;
  uint64_t found = 0;  ///< occluded rays, or hits
};

/// Traces `rays` for query `q` (not closest) with all threads.
Answers answer(Query q, const Backend& backend, std::span<const Ray> rays, Coherence coherence) {
  Answers r;
  if (q == Query::occluded) {
    r.occluded.resize(rays.size());
    occluded_parallel(backend, rays, r.occluded, coherence);
    r.found = uint64_t(std::count(r.occluded.begin(), r.occluded.end(), uint8_t(1)));
  } else if (q == Query::count) {
    r.counts.resize(rays.size());
    count_hits_parallel(backend, rays, r.counts);
    for (const uint32_t n : r.counts) r.found += n;
  } else {
    r.all = all_hits_parallel(backend, rays);
    r.found = r.all.hits.size();
  }
  return r;
}

/// The records of `answers` (of `rays`, the rays of the file from index `first` on) for a
/// query file at `path` (io/rayfile.h), as bytes, and how many.
struct QueryRecords {
  std::string bytes;
  uint64_t count = 0;
};

QueryRecords query_records(Query q, const Answers& answers, const Scene& scene, std::span<const Ray> rays,
                           uint64_t first, const std::string& path) {
  QueryRecords r;
  if (q == Query::occluded) {
    append_occluded_records(path, answers.occluded, r.bytes);
    r.count = rays.size();
  } else if (q == Query::count) {
    append_count_records(path, answers.counts, r.bytes);
    r.count = rays.size();
  } else {
    std::vector<RayHitRecord> records;
    records.reserve(answers.all.hits.size());
    for (size_t i = 0; i < rays.size(); ++i)
      for (const Hit& h : answers.all.of(i)) records.push_back({first + i, record_of(scene, rays[i], h)});
    append_all_hits_records(path, records, r.bytes);
    r.count = records.size();
  }
  return r;
}

}  // namespace

CLI::App* TraceArgs::add_to(CLI::App& app) {
  CLI::App* c =
      app.add_subcommand("trace", "Trace a ray file through a backend and write the hits (or the answers of --query)");
  add_scene_option(c, scene);
  add_time_option(c, time);
  c->add_option("--rays", rays, "Ray file: .csv, or binary (.bin, .rays)")->required();
  c->add_option("-o,--output", output, "Hit file (or the --query's file): .csv, or binary (.bin, .hits)")->required();
  add_backend_options(c, backend, variant);
  c->add_option("--query", query,
                "closest (each ray's closest hit), occluded (1 when anything is hit, else 0), count (the hits "
                "within [tnear, tfar]) or all (every hit, a record per hit)")
      ->capture_default_str();
  c->add_option("--coherence", coherence,
                "coherent (neighbouring rays as packets; closest and occluded only) or incoherent")
      ->capture_default_str();
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_trace(const TraceArgs& a, const dist::Comm& comm) {
  const bool across = comm.size() > 1, quiet = a.quiet || !comm.root();
  struct Flags {
    Coherence coherence;
    std::optional<double> time;
    Query query;
  };
  const Flags f = dist::together(comm, [&] {
    check_method("--backend", a.backend, "--variant", a.variant);
    const Flags flags{parse_coherence("--coherence", a.coherence), parse_time(a.time), parse_query(a.query)};
    if (flags.coherence == Coherence::coherent && (flags.query == Query::count || flags.query == Query::all))
      throw UsageError(cat("--coherence: coherent packets trace closest and occluded queries; --query ", a.query,
                           " traces ray by ray"));
    check_distinct_files({{"--scene", a.scene}, {"--rays", a.rays}}, {{"-o", a.output}});
    check_file_name("--rays", a.rays, check_ray_file_name);
    check_file_name("-o", a.output, check_hit_file_name);
    check_file_name("-o", a.output, check_output);  // every rank writes its share
    return flags;
  });
  const ThreadLimit limit(a.threads);
  // The scene as loaded, posed at --time before the backend is built.
  const AnimatedScene animated = dist::together(comm, [&] {
    AnimatedScene s = load_animated_scene_or_default(a.scene);
    pose(s, f.time);
    return s;
  });
  const Scene& scene = animated.scene;
  if (across) {  // each rank reads its own copies: they must be the same files
    std::vector<dist::InputDigest> inputs{{"--scene", a.scene, dist::scene_digest(scene)}};
    if (a.rays != "-")
      inputs.push_back(dist::together(comm, [&] {
        return dist::InputDigest{"--rays", a.rays, dist::file_digest(a.rays)};
      }));
    dist::check_same_inputs(comm, inputs);
  }
  // Across ranks each rank reads, traces and writes its share of the rays, in file order.
  const std::vector<Ray> rays =
      across ? dist::read_rays_across(comm, a.rays)
             : with_memory_context("reading " + a.rays, [&] { return read_rays(a.rays); });
  const auto backend = dist::together(comm, [&] { return build_backend(a.backend, a.variant, scene, a.scene); });
  // The rays before this rank's share, for the ray indices of an all-hits file.
  const uint64_t first = comm.sum_before(rays.size());
  std::vector<Hit> hits;
  Answers answers;
  const auto start = std::chrono::steady_clock::now();
  dist::together(comm, [&] {
    with_memory_context(cat("tracing ", rays.size(), " rays"), [&] {
      if (f.query != Query::closest) {
        answers = answer(f.query, *backend, rays, f.coherence);
        return;
      }
      hits.resize(rays.size());
      intersect_parallel(*backend, rays, hits, f.coherence);
      answers.found = uint64_t(std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.hit(); }));
    });
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (f.query == Query::closest) {
    const std::vector<HitRecord> records = dist::together(comm, [&] { return to_records(scene, rays, hits); });
    if (across)
      dist::write_hits_across(comm, a.output, records);
    else
      with_memory_context("writing " + a.output, [&] { write_hits(a.output, records); });
  } else {
    const QueryRecords records =
        dist::together(comm, [&] { return query_records(f.query, answers, scene, rays, first, a.output); });
    const QueryFile kind = f.query == Query::occluded ? QueryFile::occluded
                           : f.query == Query::count  ? QueryFile::count
                                                      : QueryFile::all_hits;
    const auto head = [&](uint64_t total) { return query_file_head(kind, a.output, total); };
    if (across)
      dist::write_records_across(comm, a.output, records.count, records.bytes, head);
    else
      with_memory_context("writing " + a.output, [&] { write_file(a.output, head(records.count) + records.bytes); });
  }
  uint64_t counts[] = {rays.size(), answers.found,
                       uint64_t(std::count_if(rays.begin(), rays.end(), [](const Ray& r) { return !valid_ray(r); }))};
  comm.sum(counts);
  const std::vector<double> rank_seconds = dist::gather_each(comm, seconds);
  if (!quiet) {
    const uint64_t n = counts[0], found = counts[1], invalid = counts[2];
    const double s = *std::max_element(rank_seconds.begin(), rank_seconds.end());
    std::fprintf(stderr, "raypack: traced %llu rays (%llu %s) with %s/%s in %.3f s (%.2f Mrays/s)%s; wrote %s\n",
                 (unsigned long long)n, (unsigned long long)found, f.query == Query::occluded ? "occluded" : "hits",
                 a.backend.c_str(), a.variant.c_str(), s, s > 0 ? double(n) / s * 1e-6 : 0.0,
                 across ? cat(" on ", comm.size(), " ranks").c_str() : "", a.output.c_str());
    if (invalid > 0)
      warn(invalid_rays_message(a.rays, invalid, n));
  }
  return 0;
}

}  // namespace rp::cli
