#include "cli/ranks.h"

#include <new>
#include <string>
#include <vector>

#include "base/text.h"
#include "cli/args.h"
#include "cli/out_of_memory.h"

namespace rp::cli {

dist::Failure describe_failure(std::exception_ptr failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const dist::RankFailure& e) {
    return e.failure();
  } catch (const UsageError& e) {
    return {2, one_line(e.what())};
  } catch (const Error& e) {
    return {1, one_line(e.what())};
  } catch (const std::bad_alloc&) {
    return {1, cat("out of memory: an allocation of ", failed_allocation_bytes(), " bytes failed")};
  } catch (const std::exception& e) {
    return {1, cat("internal error: ", one_line(e.what()))};
  } catch (...) {
    return {1, "internal error: an exception of unknown type"};
  }
}

void check_same_command_line(const dist::Comm& comm, int argc, char** argv) {
  if (comm.size() == 1) return;
  std::vector<std::string> mine(argv + 1, argv + argc);
  std::string packed;
  for (const std::string& arg : mine) packed += arg + '\0';
  std::string root = packed;
  comm.broadcast(root);
  dist::together(comm, [&] {
    if (packed == root) return;
    std::vector<std::string> theirs;
    for (size_t at = 0, end; at < root.size(); at = end + 1) theirs.push_back(root.substr(at, (end = root.find('\0', at)) - at));
    size_t i = 0;
    while (i < mine.size() && i < theirs.size() && mine[i] == theirs[i]) ++i;
    auto quoted = [](const std::vector<std::string>& args, size_t k) {
      return k < args.size() ? cat("'", printable(args[k]), "'") : std::string("nothing");
    };
    throw UsageError(cat("started with other arguments than rank 0 (argument ", i + 1, ": ", quoted(mine, i),
                         " where rank 0 has ", quoted(theirs, i), "); every rank must run the same raypack command"));
  });
}

}  // namespace rp::cli
