#include "sensornet/io/word_option.hpp"

#include <algorithm>
#include <cctype>
#include <utility>

namespace sensornet {
namespace {

std::string lowerCase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string joined(const std::vector<std::string>& words, const std::string& separator) {
  std::string out;
  for (const std::string& word : words) out += (out.empty() ? "" : separator) + word;
  return out;
}

}  // namespace

CLI::Validator wordCheck(std::vector<std::string> words, std::function<void(std::string&)> store) {
  return CLI::Validator(
      [words = std::move(words), store = std::move(store)](std::string& input) -> std::string {
        const std::string typed = lowerCase(input);
        const auto found = std::find_if(words.begin(), words.end(), [&typed](const std::string& w) {
          return lowerCase(w) == typed;
        });
        if (found == words.end()) return "'" + input + "' is not one of " + joined(words, ", ");
        input = *found;
        if (store) store(input);
        return {};
      },
      "");
}

std::string wordOptionText(const std::vector<std::string>& words, const std::string& default_word) {
  std::string text = "{" + joined(words, ",") + "}";
  if (!default_word.empty()) text += " [" + default_word + "]";
  return text;
}

CLI::Option* wordOption(CLI::Option* option, const std::vector<std::string>& words) {
  const std::string current = option->capture_default_str()->get_default_str();
  const bool is_a_word = std::find(words.begin(), words.end(), current) != words.end();
  option->transform(wordCheck(words));
  option->option_text(wordOptionText(words, is_a_word ? current : std::string()));
  return option;
}

}  // namespace sensornet
