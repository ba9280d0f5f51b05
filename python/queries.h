#pragma once
/// raypack.Backend's queries beyond intersect and occluded (queries.cpp): closest points,
/// distance, inside, signed distance, counts and every hit along rays (docs/queries.md).

#include <pybind11/pybind11.h>

namespace rp::python {

/// Adds the queries to raypack.Backend, which `m` must already define.
void define_queries(pybind11::module_& m);

}  // namespace rp::python
