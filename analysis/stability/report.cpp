#include <nlohmann/json.hpp>

#include <cstdio>

#include "analysis/stability.h"
#include "analysis/stability/family.h"

namespace rp::stability {

void print_table(std::FILE* out, const std::vector<Result>& results) {
  std::fprintf(out, "%-15s %-14s %-24s %7s %9s %7s %7s %7s %7s %7s %7s %7s\n", "family", "param", "method", "rays",
               "fail %", "leaks", "false", "t err", "double", "self", "nan", "out");
  for (const Result& r : results) {
    const Counts& c = r.counts;
    const std::string dbl = c.double_measured ? std::to_string(c.double_hits) : "-";
    std::fprintf(out, "%-15s %-14s %-24s %7llu %9.4f %7llu %7llu %7llu %7s %7llu %7llu %7llu\n", r.family.c_str(),
                 r.param.empty() ? "-" : r.param.c_str(), r.method.c_str(), (unsigned long long)c.rays,
                 100.0 * c.rate(), (unsigned long long)c.leaks, (unsigned long long)c.false_hits,
                 (unsigned long long)c.t_errors, dbl.c_str(), (unsigned long long)c.self_hits,
                 (unsigned long long)c.nan_hits, (unsigned long long)c.out_of_interval);
  }
}

std::string to_json(const std::vector<Result>& results, const std::string& scene_name, const Options& o) {
  nlohmann::json j;
  j["scene"] = scene_name;
  j["rays_per_family"] = o.rays;
  j["seed"] = o.seed;
  j["t_tolerance"] = o.t_tolerance;
  j["families"] = nlohmann::json::object();
  for (const FamilySpec& f : family_table()) j["families"][f.name] = f.description;
  j["results"] = nlohmann::json::array();
  for (const Result& r : results) {
    const Counts& c = r.counts;
    nlohmann::json e = {{"family", r.family}, {"param", r.param}, {"method", r.method}, {"rays", c.rays},
                        {"failed", c.failed}, {"failure_rate", c.rate()}, {"leaks", c.leaks},
                        {"false_hits", c.false_hits}, {"t_errors", c.t_errors}, {"self_hits", c.self_hits},
                        {"nan_hits", c.nan_hits}, {"out_of_interval", c.out_of_interval}};
    e["double_hits"] = c.double_measured ? nlohmann::json(c.double_hits) : nlohmann::json(nullptr);
    if (r.has_exponent) e["exponent"] = r.exponent;
    j["results"].push_back(std::move(e));
  }
  return j.dump(2) + "\n";
}

}  // namespace rp::stability
