#pragma once
/// Signatures Python's inspect module can read, for the compiled functions of the package.
///
/// pybind11 writes each function's signature, with C++ types, into the first line of its
/// docstring, where inspect.signature cannot read it: inspect takes a builtin's signature only
/// from CPython's own form, a first line "name(a, b=1, *, c=None)" followed by a line "--".
/// add_text_signatures rewrites every docstring into that form from pybind11's record of the
/// function: the py::arg names and the repr of their defaults, with the keyword-only (*) and
/// positional-only (/) markers, and no types (python/raypack/_raypack.pyi has those). Written
/// from the record the binding is made of, a signature cannot drift from the binding.

#include <pybind11/pybind11.h>

namespace rp::python {

/// Gives every function of `module`, and every method, static method and constructor of its
/// classes, a text signature (above) ahead of its documentation. Overloaded functions are left
/// as pybind11 wrote them (one signature cannot say them). Call it once, after the last
/// binding of the module is made.
void add_text_signatures(pybind11::module_& module);

}  // namespace rp::python
