#pragma once
// sensornet.World (world.cpp): the emulated world of a run, numpy arrays in and out.
#include <pybind11/pybind11.h>

namespace sensornet::python {
void bindWorld(pybind11::module_& m);
}  // namespace sensornet::python
