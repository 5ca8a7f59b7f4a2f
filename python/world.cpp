// sensornet.World: the emulated world of a run (include/sensornet/world.h) with numpy arrays in
// and out, over the C library itself, so that Python gets our agents' numbers bit for bit.
#include "world.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/world.h"

namespace py = pybind11;

namespace sensornet::python {
namespace {

class World {
 public:
  World(const std::string& yaml, std::uint64_t seed) {
    char why[512];
    world_ = sn_world_open(yaml.c_str(), seed, why, sizeof why);
    if (world_ == nullptr) throw py::value_error(why);
  }
  ~World() { sn_world_close(world_); }
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  [[nodiscard]] sn_world* get() const { return world_; }
  // Raises ValueError with the library's reason when `status` says it failed.
  void check(int status) const {
    if (status != 0) throw py::value_error(sn_world_error(world_));
  }
  [[nodiscard]] py::array_t<double> vector(std::uint32_t size) const {
    return py::array_t<double>(static_cast<py::ssize_t>(size));
  }
  [[nodiscard]] std::uint32_t dimOf(std::uint32_t sensor) const {
    const std::uint32_t p = sn_world_measurement_dim(world_, sensor);
    if (p == 0) throw py::value_error("sensor " + std::to_string(sensor) + " is not a sensor of the scenario");
    return p;
  }

 private:
  sn_world* world_ = nullptr;
};

}  // namespace

void bindWorld(py::module_& m) {
  py::class_<World>(m, "World", R"(The emulated world of a run, as our sensor agents compute it:
the plant's true state at any instant of any episode, the noise and measurements they draw, and
the arrival instants they would draw from the run's schedule versions (bit for bit).

    w = sensornet.World(scenario["yaml"], scenario["seed"])   # a Scenario sample's fields
    w.add_schedule(v["version"], v["effective_episode"], v["effective_time_s"], v["rates_hz"])
    times, versions = w.arrivals(episode, sensor)
    z = w.measure(episode, sensor, seq, times[seq])           # what our agent sends)")
      .def(py::init<const std::string&, std::uint64_t>(), py::arg("yaml"), py::arg("seed"))
      .def_property_readonly("states", [](const World& w) { return sn_world_states(w.get()); })
      .def_property_readonly("sensors", [](const World& w) { return sn_world_sensors(w.get()); })
      .def_property_readonly("horizon", [](const World& w) { return sn_world_horizon(w.get()); })
      .def("measurement_dim", [](const World& w, std::uint32_t j) { return w.dimOf(j); },
           py::arg("sensor"))
      .def("on_tick", [](const World& w, double t) { return sn_world_on_tick(w.get(), t); },
           py::arg("t"), "The instant of the plant's tick that stands for t.")
      .def(
          "state",
          [](const World& w, std::uint32_t episode, double t) {
            py::array_t<double> x = w.vector(sn_world_states(w.get()));
            w.check(sn_world_state(w.get(), episode, t, x.mutable_data()));
            return x;
          },
          py::arg("episode"), py::arg("t"), "x(t) of the episode, n values.")
      .def(
          "noise",
          [](const World& w, std::uint32_t episode, std::uint32_t sensor, std::uint64_t seq) {
            py::array_t<double> v = w.vector(w.dimOf(sensor));
            w.check(sn_world_noise(w.get(), episode, sensor, seq, v.mutable_data()));
            return v;
          },
          py::arg("episode"), py::arg("sensor"), py::arg("seq"))
      .def(
          "measure",
          [](const World& w, std::uint32_t episode, std::uint32_t sensor, std::uint64_t seq,
             double t) {
            py::array_t<double> z = w.vector(w.dimOf(sensor));
            w.check(sn_world_measure(w.get(), episode, sensor, seq, t, z.mutable_data()));
            return z;
          },
          py::arg("episode"), py::arg("sensor"), py::arg("seq"), py::arg("t"),
          "z = H_j x(t) + v, sensor j's seq-th measurement of the episode.")
      .def(
          "set_arrivals",
          [](const World& w, const std::string& mode) {
            w.check(sn_world_set_arrivals(w.get(), mode.c_str()));
          },
          py::arg("mode"), "\"poisson\" (or \"\") or \"timetable\": the Scenario's arrivals.")
      .def(
          "add_schedule",
          [](const World& w, std::uint32_t version, std::uint32_t effective_episode,
             double effective_time_s, const std::vector<double>& rates) {
            const std::size_t sensors = sn_world_sensors(w.get());
            if (rates.empty() || rates.size() % sensors != 0) {
              throw py::value_error("rates: intervals x " + std::to_string(sensors) +
                                    " values, row-major (got " + std::to_string(rates.size()) + ")");
            }
            w.check(sn_world_add_schedule(w.get(), version, effective_episode, effective_time_s,
                                          rates.data(),
                                          static_cast<std::uint32_t>(rates.size() / sensors)));
          },
          py::arg("version"), py::arg("effective_episode"), py::arg("effective_time_s"),
          py::arg("rates"), "A schedule version: rates row-major (the Schedule's rates_hz).")
      .def(
          "arrivals",
          [](const World& w, std::uint32_t episode, std::uint32_t sensor) {
            const long n = sn_world_arrivals(w.get(), episode, sensor, nullptr, nullptr, 0);
            if (n < 0) throw py::value_error(sn_world_error(w.get()));
            py::array_t<double> times(n);
            py::array_t<std::uint32_t> versions(n);
            if (n > 0) {
              (void)sn_world_arrivals(w.get(), episode, sensor, times.mutable_data(),
                                      versions.mutable_data(), static_cast<std::size_t>(n));
            }
            return py::make_tuple(times, versions);
          },
          py::arg("episode"), py::arg("sensor"),
          "(times, versions): the instants our agent transmits at, and the version of each.");
}

}  // namespace sensornet::python
