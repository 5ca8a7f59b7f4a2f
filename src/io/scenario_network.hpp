#pragma once
// The scenario file's optional `network:` section and `faults:` list (syntax in
// sensornet/core/network.hpp), read into Scenario::network and Scenario::faults. Private to
// src/io: parseScenarioYaml calls these after the plant and sensors are read, so that sensor
// indices can be checked against M. Ranges that need the horizon and grid (outage windows, crash
// instants) are checked by validateScenario.
//
//   readNetworkSection(in, root["network"], scenario);  // no-op when the node is absent
//   readFaults(in, root["faults"], scenario);

#include <yaml-cpp/yaml.h>

#include "sensornet/core/scenario.hpp"
#include "yaml_reader.hpp"

namespace sensornet {

void readNetworkSection(const YamlReader& in, const YAML::Node& network, Scenario& scenario);
void readFaults(const YamlReader& in, const YAML::Node& faults, Scenario& scenario);

}  // namespace sensornet
