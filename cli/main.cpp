// raypack's command line: one subcommand per job, each in its own *_cmd.cpp with the flags it
// registers (cli/args.h holds what they share). Only main() turns errors into an exit
// status (describe_failure, cli/ranks.h): 2 for bad flags or values (CLI11's parse
// errors and cli::UsageError), 1 for failures while running, 3 for `diff --min-agreement` not
// met. Under mpirun every rank runs main(); render, trace and diff run across the ranks.

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

#include "base/text.h"
#include "cli/args.h"
#include "cli/bench_cmd.h"
#include "cli/diff_cmd.h"
#include "cli/domains_cmd.h"
#include "cli/info_cmd.h"
#include "cli/points_cmd.h"
#include "cli/ranks.h"
#include "cli/render_cmd.h"
#include "cli/stability_cmd.h"
#include "cli/trace_cmd.h"
#include "io/output_file.h"
#include "mpi/comm.h"

namespace {

/// The command line on this rank (or this process); returns the exit status. Across MPI ranks
/// rank 0 speaks for all: it prints what every rank would (warnings, help, results, the
/// errors the ranks agreed on).
int run(const rp::dist::Comm& comm, int argc, char** argv) {
  using namespace rp::cli;
  const bool speaks = comm.root();
  if (!speaks) rp::set_warnings(false);
  std::ostringstream silent;
  std::ostream& out = speaks ? std::cout : silent;
  std::ostream& err = speaks ? std::cerr : silent;

  CLI::App app{"raypack: 8-wide SIMD ray casting beside Intel Embree"};
  app.set_version_flag("--version", std::string("raypack ") + RAYPACK_VERSION);
  app.require_subcommand(1);

  RenderArgs render_args;
  TraceArgs trace_args;
  PointsArgs points_args;
  DiffArgs diff_args;
  BenchArgs bench_args;
  ChartArgs chart_args;
  InfoArgs info_args;
  StabilityArgs stability_args;
  DomainsArgs domains_args;
  CLI::App* render = render_args.add_to(app);
  CLI::App* trace = trace_args.add_to(app);
  CLI::App* points = points_args.add_to(app);
  CLI::App* diff = diff_args.add_to(app);
  CLI::App* bench = bench_args.add_to(app);
  CLI::App* chart = chart_args.add_to(app);
  CLI::App* info = info_args.add_to(app);
  add_backends_command(app);
  CLI::App* stability = stability_args.add_to(app);
  CLI::App* domains = domains_args.add_to(app);

  try {
    check_same_command_line(comm, argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e, out, err);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e, out, err);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e, out, err);
  } catch (const CLI::ParseError& e) {
    err << "raypack: " << parse_error_message(app, e, argc, argv) << '\n';
    return 2;
  } catch (const rp::dist::RankFailure& e) {
    err << "raypack: " << e.failure().message << '\n';
    return e.failure().status;
  }
  try {
    if (*render) return run_render(render_args, comm);
    if (*trace) return run_trace(trace_args, comm);
    if (*diff) return run_diff(diff_args, comm);
    if (comm.size() > 1)
      throw UsageError(rp::cat(app.get_subcommands().front()->get_name(), " runs in one process: start it without "
                               "mpirun (render, trace and diff run across ranks)"));
    if (*info) return run_info(info_args);
    if (*points) return run_points(points_args);
    if (*bench) return run_bench(bench_args);
    if (*stability) return run_stability(stability_args);
    if (*chart) return run_chart(chart_args);
    if (*domains) return run_domains(domains_args);
    return run_backends();
  } catch (...) {
    const rp::dist::Failure f = describe_failure(std::current_exception());
    err << "raypack: " << f.message << '\n';
    return f.status;
  }
}

}  // namespace

int main(int argc, char** argv) {
  rp::install_signal_cleanup();
  std::unique_ptr<rp::dist::Comm> comm;
  try {
    comm = rp::dist::make_comm(argc, argv, rp::cli::describe_failure);
  } catch (const rp::Error& e) {
    std::cerr << "raypack: " << rp::one_line(e.what()) << '\n';
    return 1;
  }
  // Until the run's outcome is known, rank 0 says why when mpirun ends it (a rank died); once
  // known, a signal that ends it while MPI shuts down (mpirun's answer to the other ranks' exit
  // status) has nothing to add.
  if (comm->size() > 1 && comm->root())
    rp::set_signal_message(
        "raypack: rank 0 stopped by %s: under mpirun, another rank died (mpirun names it) or the "
        "run was interrupted");
  const int status = run(*comm, argc, argv);
  rp::set_signal_message("");
  comm.reset();
  return status;
}
