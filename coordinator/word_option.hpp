#pragma once
// A command-line option whose value is a word of a vocabulary (core/words.hpp): the option takes
// the words of the enum's table (any case) and says them in --help and in its error:
//
//   cmd->add_option("--on-sensor-failure", policy, "...")
//       ->transform(wordOption<FailurePolicy>())
//       ->option_text(wordOptionText(FailurePolicy::Replan));   // "replan|continue|stop [replan]"
//   // --on-sensor-failure x: "--on-sensor-failure: expected replan, continue or stop, got 'x'"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <string>
#include <type_traits>

#include "sensornet/core/words.hpp"

namespace sensornet::coordinator {

// Turns the word into the enum's number, which CLI11 then stores in the enum.
template <class E>
[[nodiscard]] CLI::Validator wordOption() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        std::string word = input;
        std::transform(word.begin(), word.end(), word.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        const auto value = lookUpWord<E>(word);
        if (!value) return "expected " + wordChoices<E>() + ", got '" + input + "'";
        input = std::to_string(static_cast<std::underlying_type_t<E>>(*value));
        return {};
      },
      "");
}

// "a|b|c [default]" for --help.
template <class E>
[[nodiscard]] std::string wordOptionText(E default_value) {
  std::string text;
  for (const WordOf<E>& w : Words<E>::kTable) text += (text.empty() ? "" : "|") + std::string(w.text);
  return text + " [" + std::string(wordOf(default_value)) + "]";
}

}  // namespace sensornet::coordinator
