#pragma once
// Words of the domain as types: an enum whose values each have one spelling in text (in reports,
// on the command line, on the wire), with one conversion each way, kept in one table. A vocabulary
// declares its table once, beside the enum:
//
//   enum class Colour { Red, Green };
//   template <> struct Words<Colour> {
//     static constexpr std::array<WordOf<Colour>, 2> kTable{{{Colour::Red, "red"},
//                                                          {Colour::Green, "green"}}};
//   };
//
// and every reader and writer of the word uses these functions:
//
//   wordOf(Colour::Red)                         // "red"
//   lookUpWord<Colour>("green")                 // Colour::Green (nullopt for an unknown word)
//   parseWord<Colour>(text, "file.json", "colour")  // or InputError "expected red or green, got 'x'"
//   wordChoices<Colour>()                       // "red or green" (for --help and errors)

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {

template <class E>
struct WordOf {
  E value;
  std::string_view text;
};

// Specialized per vocabulary with `static constexpr std::array<WordOf<E>, N> kTable`.
template <class E>
struct Words;

template <class E>
[[nodiscard]] constexpr std::string_view wordOf(E value) {
  for (const WordOf<E>& w : Words<E>::kTable) {
    if (w.value == value) return w.text;
  }
  return "unknown";
}

template <class E>
[[nodiscard]] constexpr std::optional<E> lookUpWord(std::string_view text) {
  for (const WordOf<E>& w : Words<E>::kTable) {
    if (w.text == text) return w.value;
  }
  return std::nullopt;
}

// "a, b or c": the words in table order.
template <class E>
[[nodiscard]] std::string wordChoices() {
  std::string out;
  const auto& table = Words<E>::kTable;
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (i > 0) out += i + 1 == table.size() ? " or " : ", ";
    out += table[i].text;
  }
  return out;
}

// The word's value; an InputError naming `source` and `field` with the choices otherwise.
template <class E>
[[nodiscard]] E parseWord(std::string_view text, const std::string& source,
                          const std::string& field) {
  if (const std::optional<E> value = lookUpWord<E>(text)) return *value;
  throw InputError(source, field, wordChoices<E>() + ", got '" + std::string(text) + "'");
}

// The words in table order, for CLI11's IsMember.
template <class E>
[[nodiscard]] std::vector<std::string> wordTexts() {
  std::vector<std::string> out;
  for (const WordOf<E>& w : Words<E>::kTable) out.emplace_back(w.text);
  return out;
}

// The table as a map from text, for CLI11's CheckedTransformer.
template <class E>
[[nodiscard]] std::map<std::string, E> wordMap() {
  std::map<std::string, E> out;
  for (const WordOf<E>& w : Words<E>::kTable) out.emplace(std::string(w.text), w.value);
  return out;
}

}  // namespace sensornet
