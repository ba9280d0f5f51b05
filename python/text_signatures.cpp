#include "python/text_signatures.h"

#include <cstdlib>
#include <cstring>
#include <string>

namespace rp::python {

namespace py = pybind11;

namespace {

/// "(self, origins, directions=None, *, threads=0)": the parameters of `rec` in the text
/// signature form of CPython (Objects/typeobject.c, find_signature), as pybind11 orders them.
std::string text_signature(const py::detail::function_record& rec) {
  std::string s = "(";
  for (size_t i = 0; i < rec.nargs; ++i) {
    if (i > 0) s += ", ";
    if (i == rec.nargs_pos) s += "*, ";
    if (i < rec.args.size() && rec.args[i].name)
      s += rec.args[i].name;
    else
      s += i == 0 && rec.is_method ? std::string("self") : "arg" + std::to_string(i);
    if (i < rec.args.size() && rec.args[i].descr) s += std::string("=") + rec.args[i].descr;
    if (rec.nargs_pos_only > 0 && i + 1 == rec.nargs_pos_only) s += ", /";
  }
  return s + ")";
}

/// Rewrites the docstring of `object` when it is a pybind11 function (or a method or static
/// method wrapping one) of one overload without *args or **kwargs.
void rewrite(py::handle object) {
  if (PyObject_TypeCheck(object.ptr(), &PyStaticMethod_Type)) object = object.attr("__func__");
  const py::handle function = py::detail::get_function(object);
  if (!function || !PyCFunction_Check(function.ptr())) return;
  PyObject* const self = PyCFunction_GET_SELF(function.ptr());
  if (!self || !PyCapsule_CheckExact(self)) return;
  const auto capsule = py::reinterpret_borrow<py::capsule>(self);
  if (!py::detail::is_function_record_capsule(capsule)) return;
  const auto* rec = capsule.get_pointer<py::detail::function_record>();
  if (rec->next || rec->has_args || rec->has_kwargs) return;
  const std::string doc = std::string(rec->name) + text_signature(*rec) + "\n--\n\n" + (rec->doc ? rec->doc : "");
  // pybind11 allocated the docstring with strdup and frees it with the function (std::free).
  PyMethodDef* const def = reinterpret_cast<PyCFunctionObject*>(function.ptr())->m_ml;
  std::free(const_cast<char*>(def->ml_doc));
  def->ml_doc = strdup(doc.c_str());
}

}  // namespace

void add_text_signatures(py::module_& module) {
  for (const auto& [name, value] : module.attr("__dict__").cast<py::dict>()) {
    if (PyType_Check(value.ptr())) {
      for (const auto& [member, attribute] : value.attr("__dict__").cast<py::dict>()) rewrite(attribute);
    } else {
      rewrite(value);
    }
  }
}

}  // namespace rp::python
