#pragma once
// sensornet's math from Python (math_bindings.cpp): scenarios, plans, brackets, the Monte Carlo
// and the closed loop of `fusion_center evaluate`, the surrogates' trajectories and the exact
// CD-KF, numpy arrays in and out.
#include <pybind11/pybind11.h>

namespace sensornet::python {
void bindMath(pybind11::module_& m);
}  // namespace sensornet::python
