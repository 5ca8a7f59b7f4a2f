#pragma once
// Parsing a YAML document from text with the one error every input file of sensornet gives for
// broken YAML: InputError("<source>:<line>", "", "valid YAML (<parser's message>)").
//
//   const YAML::Node root = parseYamlText(readTextFile(path, "hosts"), path);

#include <yaml-cpp/yaml.h>

#include <string>

namespace sensornet {

// Throws InputError naming `source` and the line when `text` is not valid YAML.
[[nodiscard]] YAML::Node parseYamlText(const std::string& text, const std::string& source);

}  // namespace sensornet
