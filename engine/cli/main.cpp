// raypack's command line: one subcommand per job, each in its own *_cmd.cpp with the flags it
// registers (engine/cli/args.h holds what they share). Only main() turns errors into an exit
// status: 2 for bad flags or values (CLI11's parse errors and cli::UsageError), 1 for failures
// while running, 3 for `diff --min-agreement` not met.

#include <CLI/CLI.hpp>
#include <iostream>
#include <new>
#include <string>
#include <utility>

#include "engine/cli/args.h"
#include "engine/cli/bench_cmd.h"
#include "engine/cli/diff_cmd.h"
#include "engine/cli/info_cmd.h"
#include "engine/cli/out_of_memory.h"
#include "engine/cli/plot.h"
#include "engine/cli/render_cmd.h"
#include "engine/cli/stability_cmd.h"
#include "engine/cli/trace_cmd.h"
#include "engine/output_file.h"
#include "engine/text.h"

int main(int argc, char** argv) {
  using namespace rp::cli;
  rp::install_signal_cleanup();
  CLI::App app{"raypack: 8-wide SIMD ray casting beside Intel Embree"};
  app.set_version_flag("--version", std::string("raypack ") + RAYPACK_VERSION);
  app.require_subcommand(1);

  RenderArgs render_args;
  TraceArgs trace_args;
  DiffArgs diff_args;
  BenchArgs bench_args;
  ChartArgs chart_args;
  InfoArgs info_args;
  StabilityArgs stability_args;
  CLI::App* render = render_args.add_to(app);
  CLI::App* trace = trace_args.add_to(app);
  CLI::App* diff = diff_args.add_to(app);
  CLI::App* bench = bench_args.add_to(app);
  CLI::App* chart = chart_args.add_to(app);
  CLI::App* info = info_args.add_to(app);
  add_backends_command(app);
  CLI::App* stability = stability_args.add_to(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "raypack: " << parse_error_message(app, e, argc, argv) << '\n';
    return 2;
  }
  try {
    // A chart format the extension does not name is a bad flag, found before any work.
    for (const auto& [flag, file] : {std::pair{"--chart", bench_args.chart}, std::pair{"--chart", stability_args.chart},
                                     std::pair{"-o", *chart ? chart_args.output : std::string()}}) {
      if (file.empty()) continue;
      try {
        chart_format(file);
      } catch (const rp::Error& e) {
        throw UsageError(rp::cat(flag, ": ", e.what()));
      }
    }
    if (*render) return run_render(render_args);
    if (*trace) return run_trace(trace_args);
    if (*diff) return run_diff(diff_args);
    if (*info) return run_info(info_args);
    if (*bench) return run_bench(bench_args);
    if (*stability) return run_stability(stability_args);
    if (*chart) return run_chart(chart_args);
    return run_backends();
  } catch (const UsageError& e) {
    std::cerr << "raypack: " << rp::one_line(e.what()) << '\n';
    return 2;
  } catch (const rp::Error& e) {
    std::cerr << "raypack: " << rp::one_line(e.what()) << '\n';
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "raypack: out of memory: an allocation of " << failed_allocation_bytes() << " bytes failed\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "raypack: internal error: " << rp::one_line(e.what()) << '\n';
    return 1;
  }
}
