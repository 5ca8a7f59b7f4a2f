#pragma once
// Reading typed values out of a YAML tree for the scenario file: every failure throws InputError
// naming the file, the line and the field path. Private to src/io.
//
//   const YamlReader in("my.yaml");
//   const double horizon = in.number(in.required(root, "horizon", "horizon"), "horizon");
//   in.rejectUnknownKeys(root["plant"], "plant", {"A", "Q", "P0", "m0"});

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <utility>

#include "sensornet/core/input_error.hpp"

namespace sensornet {

// A number shown in an error message: cut short when it is long (400 digits).
inline std::string shortened(const std::string& text) {
  constexpr std::size_t kShown = 30;
  if (text.size() <= kShown) return text;
  return text.substr(0, kShown) + "... (" + std::to_string(text.size()) + " characters)";
}

// Reads typed values out of a YAML tree; every failure names the file, line and field path.
class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& field,
                         const std::string& expected) const {
    std::string where = source_;
    if (node.IsDefined() && node.Mark().line >= 0) {
      where += ":" + std::to_string(node.Mark().line + 1);
    }
    throw InputError(where, field, expected);
  }

  YAML::Node required(const YAML::Node& parent, const std::string& key,
                      const std::string& field) const {
    const YAML::Node child = parent[key];
    if (!child.IsDefined() || child.IsNull()) fail(parent, field, "a value (the field is missing)");
    return child;
  }

  double number(const YAML::Node& node, const std::string& field) const {
    if (!node.IsScalar()) fail(node, field, "a number");
    const std::string& text = node.Scalar();
    // yaml-cpp accepts .inf/.nan; we reject every non-finite number explicitly.
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      // yaml-cpp refuses a number too large for a double (1e309) like any other text.
      char* end = nullptr;
      const double parsed = std::strtod(text.c_str(), &end);
      if (!text.empty() && *end == '\0' && std::isinf(parsed)) {
        fail(node, field,
             "a finite number, got '" + shortened(text) + "' (the number overflows a double)");
      }
      fail(node, field, "a number, got '" + shortened(text) + "'");
    }
    if (!std::isfinite(value)) fail(node, field, "a finite number, got '" + text + "'");
    return value;
  }

  long integer(const YAML::Node& node, const std::string& field) const {
    const double value = number(node, field);
    if (value != std::floor(value) || std::abs(value) > 1e15) {
      fail(node, field, "an integer, got '" + node.Scalar() + "'");
    }
    return static_cast<long>(value);
  }

  Eigen::MatrixXd matrix(const YAML::Node& node, const std::string& field) const {
    if (!node.IsSequence() || node.size() == 0) fail(node, field, "a non-empty list of rows");
    const auto rows = static_cast<Eigen::Index>(node.size());
    Eigen::Index cols = -1;
    Eigen::MatrixXd m;
    for (Eigen::Index i = 0; i < rows; ++i) {
      const YAML::Node row = node[static_cast<std::size_t>(i)];
      const std::string row_field = field + "[" + std::to_string(i) + "]";
      if (!row.IsSequence()) fail(row, row_field, "a row: a list of numbers");
      if (cols < 0) {
        cols = static_cast<Eigen::Index>(row.size());
        if (cols == 0) fail(row, row_field, "a non-empty row");
        m.resize(rows, cols);
      } else if (static_cast<Eigen::Index>(row.size()) != cols) {
        fail(row, row_field,
             std::to_string(cols) + " entries like row 0, got " + std::to_string(row.size()));
      }
      for (Eigen::Index j = 0; j < cols; ++j) {
        m(i, j) =
            number(row[static_cast<std::size_t>(j)], row_field + "[" + std::to_string(j) + "]");
      }
    }
    return m;
  }

  Eigen::VectorXd vector(const YAML::Node& node, const std::string& field) const {
    if (!node.IsSequence() || node.size() == 0) fail(node, field, "a non-empty list of numbers");
    Eigen::VectorXd v(static_cast<Eigen::Index>(node.size()));
    for (std::size_t i = 0; i < node.size(); ++i) {
      v(static_cast<Eigen::Index>(i)) = number(node[i], field + "[" + std::to_string(i) + "]");
    }
    return v;
  }

  void rejectUnknownKeys(const YAML::Node& node, const std::string& field,
                         std::initializer_list<const char*> known) const {
    if (!node.IsMap()) fail(node, field.empty() ? "(top level)" : field, "a mapping of keys");
    for (const auto& entry : node) {
      const std::string key = entry.first.as<std::string>();
      bool ok = false;
      for (const char* k : known) ok = ok || key == k;
      if (!ok) {
        std::string list;
        for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(entry.first, field.empty() ? key : field + "." + key,
             "one of the known keys (" + list + "), got unknown key '" + key + "'");
      }
    }
  }

  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

}  // namespace sensornet
