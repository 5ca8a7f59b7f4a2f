#include "sensornet/launcher/outside_roles.hpp"

#include "sensornet/dds/domain.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/launcher/host_placement.hpp"

namespace sensornet::launcher {

namespace fs = std::filesystem;

fs::path outsideConfigFile(const fs::path& log_dir, const wire::RunOptions& run, bool placed) {
  if (placed) return fs::absolute(log_dir / "cyclone-launcher.xml");
  const std::string chosen = run.chosenCycloneConfig();
  if (chosen.rfind("file://", 0) == 0) return chosen.substr(7);
  if (!chosen.empty() && chosen.find('<') == std::string::npos) return fs::absolute(chosen);
  const fs::path path = fs::absolute(log_dir / "cyclone-outside.xml");
  replaceFileAtomically(path, (chosen.empty() ? dds::loopbackConfigXml() : chosen) + "\n");
  return path;
}

namespace {

// The environment assignment that loads the run's configuration, as a shell reads it.
std::string cycloneUri(const OutsideReach& reach) {
  return "CYCLONEDDS_URI=" + shellLine({"file://" + reach.cyclone_config.string()});
}

}  // namespace

std::string outsideRolesAnnouncement(const OutsideRoles& roles, const OutsideReach& reach) {
  const std::string domain = std::to_string(reach.domain_id);
  std::string text;
  if (!roles.any()) return text;
  if (!roles.sensors.empty()) {
    text += "sensornet: sensors " + emulator::formatSensorIds(roles.sensors) +
            " are external: the run waits (up to the coordinator's ready timeout) for a "
            "participant on DDS domain " + domain + " that writes for them in partition " +
            reach.partition + "/sensors/<their ids> (docs/wire-protocol.md, \"Sensor\")\n";
  }
  if (roles.fusion_center) {
    text += "sensornet: the fusion center is external: the run waits (up to the coordinator's "
            "ready timeout) for a participant on DDS domain " + domain +
            " that reads the run in partition " + reach.partition +
            " and writes Report and FusionState there (docs/wire-protocol.md, \"Fusion center\")" +
            (roles.reference_fusion ? "; ours runs beside it as the reference" : "") + "\n";
  }
  text += "sensornet: an outside participant loads this run's Cyclone configuration: " +
          cycloneUri(reach) + "\n";
  return text;
}

std::string outsideRolesAdvice(const OutsideReach& reach,
                               const Scenario& scenario, const std::vector<int>& silent_sensors,
                               bool fusion_center_silent) {
  if (silent_sensors.empty() && !fusion_center_silent) return "";
  const std::string uri = cycloneUri(reach);
  std::string who = silent_sensors.empty()
                        ? std::string()
                        : "external sensors " + emulator::formatSensorIds(silent_sensors);
  if (fusion_center_silent) who += (who.empty() ? "" : " and ") + std::string("the fusion center");
  std::string text =
      "sensornet: nothing has spoken for " + who + " yet. An outside participant must join DDS "
      "domain " + std::to_string(reach.domain_id) + ", partition " + reach.partition +
      (silent_sensors.empty() ? "" : " (a sensor's writers in " + reach.partition + "/sensors/<id>)") +
      ", with this run's Cyclone configuration: " + uri +
      " (Cyclone's default configuration hears nothing of this run)\n";
  if (!silent_sensors.empty()) {
    const int j = silent_sensors.front();
    const auto dim = j >= 0 && j < scenario.sensorCount()
                         ? scenario.sensors[static_cast<std::size_t>(j)].H.rows()
                         : 1;
    std::vector<std::string> argv = {"external_sensor"};
    argv.insert(argv.end(), reach.run_flags.begin(), reach.run_flags.end());
    argv.insert(argv.end(), {"--sensor", std::to_string(j), "--dim", std::to_string(dim)});
    text += "  the C example (examples/c/external_sensor.c) fills sensor " + std::to_string(j) +
            "'s role: " + uri + " " + shellLine(argv) + "\n";
  }
  return text;
}

}  // namespace sensornet::launcher
