#include "cli/pareto.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "base/error.h"
#include "cli/plot.h"
#include "io/input_file.h"
#include "io/json_text.h"
#include "io/ordered_json.h"

namespace rp::cli {

namespace {

using Json = nlohmann::ordered_json;

bool is_hard(const std::string& family, const std::string& param) {
  if (family == "edges" || family == "vertices" || family == "grazing") return param.empty();
  return family == "translated" && param == "1e6";
}

}  // namespace

std::map<std::string, HardFailures> read_hard_failures(const std::string& path) {
  const std::string text = read_file(path);
  check_json_depth(path, text);
  std::map<std::string, HardFailures> out;
  try {
    const Json j = parse_ordered_json(text);
    if (!(j.is_object() && j.contains("results") && j["results"].is_array()))
      throw Error(cat(path, ": not a raypack stability file (no \"results\")"));
    for (const Json& r : j["results"]) {
      if (!is_hard(r.at("family").get<std::string>(), r.at("param").get<std::string>())) continue;
      const std::string method = r.at("method").get<std::string>();
      HardFailures& f = out[method.substr(0, method.find(':'))];
      f.failed += r.at("failed").get<double>();
      f.rays += r.at("rays").get<double>();
    }
  } catch (const Json::exception& e) {
    throw Error(cat(path, ": not a raypack stability file: ", json_reason(e.what())));
  }
  if (out.empty()) throw Error(cat(path, ": no results of the families ", kHardFamilies));
  return out;
}

std::string draw_pareto(const Json& bench, const std::string& stability_path, const std::string& chart) {
  namespace fs = std::filesystem;
  const std::map<std::string, HardFailures> failures = read_hard_failures(stability_path);
  const std::string out = companion_chart(chart, "-pareto");
  constexpr double kFloor = 1e-5;  // where a zero failure rate is drawn

  // Per ray kind and method: the log-sum of its fastest method's rate over the scenes.
  std::vector<std::string> kinds, methods, scene_names;
  std::map<std::pair<std::string, std::string>, std::pair<double, int>> speed;  // (kind, method) -> (sum log, scenes)
  for (const Json& sc : bench["scenes"]) {
    scene_names.push_back(sc["scene"].get<std::string>());
    std::map<std::pair<std::string, std::string>, double> best;
    for (const Json& r : sc["results"]) {
      const std::string kind = r["kind"].get<std::string>(), method = r["backend"].get<std::string>();
      if (!failures.contains(method) || !(failures.at(method).rays > 0)) continue;
      if (std::ranges::count(kinds, kind) == 0) kinds.push_back(kind);
      if (std::ranges::count(methods, method) == 0) methods.push_back(method);
      double& b = best[{kind, method}];
      b = std::max(b, r["mrays_per_s"].get<double>());
    }
    for (const auto& [key, mrays] : best)
      if (mrays > 0) {
        auto& [sum, n] = speed[key];
        sum += std::log(mrays);
        ++n;
      }
  }
  if (methods.empty())
    throw Error(cat(stability_path,
                    ": no method in common with the bench results (the bench's \"backend\" keys, e.g. "
                    "simd/watertight, against the stability file's methods' backend/variant)"));

  std::string scenes_text;
  for (const std::string& s : scene_names) scenes_text += (scenes_text.empty() ? "" : ", ") + fs::path(s).filename().string();
  constexpr int kPanelW = 560, kPanelH = 460, kLegendW = 240, kTitleH = 70;
  const int width = kPanelW * int(kinds.size()) + kLegendW, height = kPanelH + kTitleH;
  std::ostringstream g, plots;
  for (size_t k = 0; k < kinds.size(); ++k) {
    // The points, then the front: sorted by speed, fastest first, a point is on the front when
    // it fails less than every faster one.
    std::vector<std::pair<double, double>> front;
    std::string plot;
    std::vector<std::tuple<double, double, size_t>> points;
    for (size_t m = 0; m < methods.size(); ++m) {
      const auto it = speed.find({kinds[k], methods[m]});
      if (it == speed.end()) continue;
      const HardFailures& f = failures.at(methods[m]);
      points.emplace_back(std::exp(it->second.first / it->second.second), std::max(kFloor, f.failed / f.rays), m);
    }
    std::ranges::sort(points, [](const auto& a, const auto& b) { return std::get<0>(a) > std::get<0>(b); });
    double least = 2;
    for (const auto& [x, y, m] : points) {
      g << "$k" << k << "m" << m << " << EOD\n" << x << ' ' << y << "\nEOD\n";
      plot += cat(plot.empty() ? "plot " : ", ", "$k", k, "m", m, " using 1:2 with points ps 2", point_style(m), " notitle");
      if (y < least) {
        front.emplace_back(x, y);
        least = y;
      }
    }
    g << "$front" << k << " << EOD\n";
    for (const auto& [x, y] : front) g << x << ' ' << y << "\n";
    g << "EOD\n";
    plots << "set origin " << double(kPanelW) * double(k) / width << ",0\nset size " << double(kPanelW) / width << ","
          << double(kPanelH) / height << "\n";
    plots << "set title " << gnuplot_string(kinds[k] + " rays") << "\n";
    plots << plot << ", $front" << k << " using 1:2 with steps dt 2 lc rgb '#999999' notitle\n";
  }
  g << "set multiplot title "
    << gnuplot_string(cat("raypack: speed against exactness. x: Mrays/s of each method's fastest way, geometric mean over ",
                          scenes_text, ". y: failure rate on ", kHardFamilies, " (",
                          fs::path(stability_path).filename().string(), "). Dashed: the Pareto front"))
    << " font ',11'\n";
  g << "set logscale y\nset yrange [" << kFloor / 3 << ":1]\nset format y '%.0e'\nset grid\nset key off\n";
  g << "set xlabel 'Mrays/s'\nset ylabel 'failure rate, hard families'\n";
  g << "set ytics add ('0' " << kFloor << ")\n";
  g << "set offsets graph 0.08, graph 0.08, 0, 0\n";
  g << plots.str();
  g << legend_cell(methods, double(kPanelW) * double(kinds.size()) / width, 0.0, double(kLegendW) / width,
                   double(kPanelH) / height);
  g << "unset multiplot\n";
  plot_to(out, cat(width, ",", height), g.str());
  return out;
}

}  // namespace rp::cli
