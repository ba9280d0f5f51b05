#pragma once
/// raypack.Scene's bindings (scene.cpp): loading, scenes from arrays and built piece by piece,
/// vertices, transforms, geometry ids and masks.

#include <pybind11/pybind11.h>

namespace rp::python {

/// Defines raypack.Scene and raypack.load_scene in `m`, before the classes that return scenes.
void define_scene(pybind11::module_& m);

}  // namespace rp::python
