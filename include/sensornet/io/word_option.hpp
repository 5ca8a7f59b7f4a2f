#pragma once
// A command-line option whose value is one word of a fixed list: a vocabulary's words
// (core/words.hpp) for an enum, or a plain list for a string or number option. Every program's
// word options go through here, so that --help shows the words and a bad one is one line:
//
//   wordOption<FailurePolicy>(cmd->add_option("--on-sensor-failure", policy, "..."));
//   //   --help:  --on-sensor-failure {replan,continue,stop} [replan]
//   //   --on-sensor-failure x:
//   //     "--on-sensor-failure: 'x' is not one of replan, continue, stop"
//   wordOption(cmd->add_option("--key", key, "..."), {"ec", "rsa"});   // a std::string option
//
// Words are taken in any case ("Replan") and stored as the list spells them.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "sensornet/core/words.hpp"

namespace sensornet {

// Takes a value that is one of `words` (any case), rewrites it as the list spells it, then
// hands it to `store` (which may rewrite it further: an enum's number); refuses any other value
// with "'x' is not one of a, b, c".
[[nodiscard]] CLI::Validator wordCheck(std::vector<std::string> words,
                                       std::function<void(std::string&)> store = {});

// "{a,b,c}" and, when `default_word` is not empty, " [default]": what --help shows.
[[nodiscard]] std::string wordOptionText(const std::vector<std::string>& words,
                                         const std::string& default_word);

// Makes `option` take one of `words`; its current value (if any) is shown as the default.
CLI::Option* wordOption(CLI::Option* option, const std::vector<std::string>& words);

// Makes `option`, which stores an enum E, take the words of E's table; the option's current
// value is shown as the default.
template <class E>
CLI::Option* wordOption(CLI::Option* option) {
  static_assert(std::is_enum_v<E>, "wordOption<E>: E is a vocabulary enum");
  using Number = std::underlying_type_t<E>;
  // CLI11 keeps the default of an enum as its number ("1"); say it as the word.
  const std::string number = option->capture_default_str()->get_default_str();
  std::string shown_default;
  for (const WordOf<E>& w : Words<E>::kTable) {
    if (std::to_string(static_cast<Number>(w.value)) == number) shown_default = w.text;
  }
  const std::vector<std::string> words = wordTexts<E>();
  option->transform(wordCheck(words, [](std::string& word) {
    word = std::to_string(static_cast<Number>(*lookUpWord<E>(word)));  // CLI11 stores the number
  }));
  option->option_text(wordOptionText(words, shown_default));
  return option;
}

}  // namespace sensornet
