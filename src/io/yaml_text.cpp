#include "sensornet/io/yaml_text.hpp"

#include "sensornet/core/input_error.hpp"

namespace sensornet {

YAML::Node parseYamlText(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(source + ":" + std::to_string(e.mark.line + 1), "",
                     "valid YAML (" + e.msg + ")");
  }
}

}  // namespace sensornet
