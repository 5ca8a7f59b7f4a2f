#pragma once
// The one exception type for bad input. Its message names where the input came from (a file, a
// command-line flag, a message), the field, and what was expected, so that `main` can print it
// as one line and exit non-zero:
//
//   throw InputError("scenario.yaml", "plant.P0", "positive definite (smallest eigenvalue -1)");
//   // what(): "scenario.yaml: plant.P0: expected positive definite (smallest eigenvalue -1)"

#include <stdexcept>
#include <string>

namespace sensornet {

class InputError : public std::runtime_error {
 public:
  InputError(const std::string& source, const std::string& field, const std::string& expected)
      : std::runtime_error(compose(source, field, expected)), field_(field), expected_(expected) {}

  [[nodiscard]] const std::string& field() const noexcept { return field_; }
  [[nodiscard]] const std::string& expected() const noexcept { return expected_; }
  // The same error, attributed to a more precise source (for example "file.yaml:12").
  [[nodiscard]] InputError relocated(const std::string& source) const {
    return InputError(source, field_, expected_);
  }

 private:
  static std::string compose(const std::string& source, const std::string& field,
                             const std::string& expected) {
    std::string message;
    if (!source.empty()) message += source + ": ";
    if (!field.empty()) message += field + ": ";
    return message + "expected " + expected;
  }
  std::string field_;
  std::string expected_;
};

}  // namespace sensornet
