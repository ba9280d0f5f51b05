#pragma once
/// Judging a family of `raypack stability`: each method's answer for each ray against the
/// double-precision reference (the rules in classify(), judge.cpp). Internal to analysis.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "analysis/stability.h"
#include "analysis/stability/family.h"

namespace rp::stability {

/// Runs one family: the reference, every backend of `o` (built once per scene into
/// `backends`), every scalar method whose primitive kind the rays' fans hold; appends a Result
/// per method to `out`.
void evaluate(const Family& f, const Reference& reference, const Options& o,
              std::map<std::string, MethodBackend>& backends, std::vector<Result>& out);

/// Names of the scalar methods, in the order evaluate() runs them.
std::vector<std::string> scalar_method_names();

}  // namespace rp::stability
