// The Python module sensornet._sensornet: LaunchedRun of sensornet::testing (launched_run.hpp)
// for Python test suites, Participant (participant.hpp), a DDS participant of a run, World
// (world.hpp), and the math of the programs (math_bindings.hpp). The package sensornet (python/sensornet/__init__.py) wraps it with
// keyword arguments, a context manager and the report as a dict; sensornet.pytest_plugin
// gives the pytest fixture.
#include <pybind11/chrono.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>

#include "math_bindings.hpp"
#include "participant.hpp"
#include "world.hpp"
#include "sensornet/testing/launched_run.hpp"

namespace py = pybind11;
namespace st = sensornet::testing;

PYBIND11_MODULE(_sensornet, m) {
  m.doc() = "sensornet's launch fixture (sensornet::testing::LaunchedRun) and a participant of a run";
  sensornet::python::bindParticipant(m);
  sensornet::python::bindWorld(m);
  sensornet::python::bindMath(m);
  py::class_<st::LaunchOptions>(m, "LaunchOptions")
      .def(py::init<>())
      .def_readwrite("program", &st::LaunchOptions::program)
      .def_readwrite("scenario", &st::LaunchOptions::scenario)
      .def_readwrite("episodes", &st::LaunchOptions::episodes)
      .def_readwrite("time_scale", &st::LaunchOptions::time_scale)
      .def_readwrite("seed", &st::LaunchOptions::seed)
      .def_readwrite("external_sensors", &st::LaunchOptions::external_sensors)
      .def_readwrite("external_fusion_center", &st::LaunchOptions::external_fusion_center)
      .def_readwrite("reference_fusion", &st::LaunchOptions::reference_fusion)
      .def_readwrite("require", &st::LaunchOptions::require)
      .def_readwrite("extra_args", &st::LaunchOptions::extra_args)
      .def_readwrite("timeout", &st::LaunchOptions::timeout);
  py::class_<st::LaunchedRun>(m, "LaunchedRun")
      .def(py::init<st::LaunchOptions>(), py::arg("options"))
      .def_property_readonly("run_id", &st::LaunchedRun::runId)
      .def_property_readonly("log_dir", &st::LaunchedRun::logDir)
      .def_property_readonly("launcher_pid", &st::LaunchedRun::launcherPid)
      .def("keep_files", &st::LaunchedRun::keepFiles)
      // The exit code, the launcher's output and errors, and the report as JSON text.
      .def(
          "wait",
          [](st::LaunchedRun& run) {
            const st::RunResult* r = nullptr;
            {
              py::gil_scoped_release unlocked;  // a run takes seconds: let other threads go on
              r = &run.wait();
            }
            return py::make_tuple(r->exit_code, r->output, r->errors, r->report.dump());
          });
}
