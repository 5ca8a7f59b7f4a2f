#pragma once
// What the launcher tells the user about roles that outside code fills (--external-sensors,
// --external-fusion-center): when the run starts, one line per role naming the domain and the
// partition; and, when no participant has spoken for a role after a few seconds, everything an
// outside participant must have to be heard: the domain, the partitions, the Cyclone
// configuration file (with Cyclone's default configuration a participant hears nothing of a
// run on the loopback configuration) and the command line of the C example that fills the role.
//
//   const OutsideReach reach{domain_id, partition, config_file, {"--run-id", id, "--domain-id", d}};
//   announce(outsideRolesAnnouncement(roles, reach));
//   ... after kOutsideAdviceDelay with sensors 1 and 3 silent:
//   print(outsideRolesAdvice(reach, scenario, {1, 3}, false));

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "sensornet/core/scenario.hpp"
#include "sensornet/wire/run_options.hpp"

namespace sensornet::launcher {

struct OutsideRoles {
  std::vector<int> sensors;    // --external-sensors, sorted
  bool fusion_center = false;  // --external-fusion-center
  bool reference_fusion = false;  // ours runs beside the external one
  [[nodiscard]] bool any() const { return !sensors.empty() || fusion_center; }
};

// Where the run is, as an outside participant on this host must name it.
struct OutsideReach {
  int domain_id = 0;
  std::string partition;                // sensornet/<run id>
  std::filesystem::path cyclone_config;  // the file its CYCLONEDDS_URI must name
  std::vector<std::string> run_flags;   // --run-id ID --domain-id D for the C examples
};

// The Cyclone configuration file an outside participant of this run must load: the launcher's
// across hosts (`placed`: <log_dir>/cyclone-launcher.xml), the one given as a file, else the
// shipped loopback one (or the XML given) written to <log_dir>/cyclone-outside.xml.
[[nodiscard]] std::filesystem::path outsideConfigFile(const std::filesystem::path& log_dir,
                                                      const wire::RunOptions& run, bool placed);

// The silence after which the launcher says what an outside participant needs.
inline constexpr std::chrono::seconds kOutsideAdviceDelay{5};

// The lines printed when the run starts, the configuration to load among them ("" when no role
// is outside).
[[nodiscard]] std::string outsideRolesAnnouncement(const OutsideRoles& roles,
                                                   const OutsideReach& reach);

// What a participant for the silent roles must have, with the C example's command line for the
// first silent sensor (its measurement dimension from `scenario`); "" when none is silent.
[[nodiscard]] std::string outsideRolesAdvice(const OutsideReach& reach,
                                             const Scenario& scenario,
                                             const std::vector<int>& silent_sensors,
                                             bool fusion_center_silent);

}  // namespace sensornet::launcher
