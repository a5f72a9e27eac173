#include "usage.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <tuple>

namespace vsd::cli {

namespace {

/// Renamed flags (docs/cli.md "Vocabulary"): (subcommand path, old spelling, new spelling).
struct Rename {
  const char* command;
  const char* oldName;
  const char* newName;
};
constexpr Rename kRenames[] = {
    {"predict", "--samples", "--futures"},     {"predict", "--sample-seed", "--future-seed"},
    {"compare", "--draws", "--futures"},       {"compare", "--draw-seed", "--future-seed"},
    {"search", "--future-samples", "--futures"}, {"run", "--batch", "--net-batch"},
    {"run", "-b", "--net-batch"},              {"train", "--batch", "--minibatch"},
    {"bench run", "--batch", "--net-batch"},   {"bench isolation", "--batch", "--net-batch"},
    {"bench model", "--draws", "--futures"},   {"bench train", "--batch", "--minibatch"},
    {"bench search", "--future-samples", "--futures"},
};

/// Optimal string alignment distance (a swap of neighbours counts 1: "rnu" -> "run").
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

/// The subcommand path of `app` ("scenario export"), without the program.
std::string pathOf(const CLI::App* app) {
  std::string path;
  for (; app != nullptr && app->get_parent() != nullptr; app = app->get_parent()) {
    path = path.empty() ? app->get_name() : app->get_name() + " " + path;
  }
  return path;
}

CLI::App* subcommandNamed(CLI::App* app, const std::string& name) {
  for (auto* command : app->get_subcommands([](CLI::App*) { return true; })) {
    if (command->get_name() == name) return command;
  }
  return nullptr;
}

/// The option `name` ("--out", "-o") of `app` or of a parent it falls through to.
const CLI::Option* optionNamed(CLI::App* app, const std::string& name) {
  for (; app != nullptr; app = app->get_parent()) {
    if (const auto* option = app->get_option_no_throw(name)) return option;
  }
  return nullptr;
}

std::vector<std::string> optionNames(CLI::App* app) {
  std::vector<std::string> names;
  for (; app != nullptr; app = app->get_parent()) {
    for (const auto* option : app->get_options()) {
      for (const auto& name : option->get_lnames()) names.push_back("--" + name);
      for (const auto& name : option->get_snames()) names.push_back("-" + name);
    }
  }
  return names;
}

std::vector<std::string> subcommandNames(CLI::App* app) {
  std::vector<std::string> names;
  for (auto* command : app->get_subcommands([](CLI::App*) { return true; })) names.push_back(command->get_name());
  return names;
}

std::string unknownSubcommand(CLI::App* app, const std::string& word) {
  const std::string where = pathOf(app).empty() ? std::string() : pathOf(app) + ": ";
  const auto known = subcommandNames(app);
  const std::string near = nearestWord(word, known);
  if (!near.empty()) return fmt::format("{}unknown subcommand '{}' — did you mean '{}'?", where, word, near);
  return fmt::format("{}unknown subcommand '{}'; the subcommands are {}", where, word, fmt::join(known, ", "));
}

std::string unknownOption(CLI::App* app, const std::string& word) {
  const std::string where = pathOf(app).empty() ? std::string() : pathOf(app) + ": ";
  const std::string near = nearestWord(word, optionNames(app));
  if (!near.empty()) return fmt::format("{}unknown option '{}' — did you mean '{}'?", where, word, near);
  return fmt::format("{}unknown option '{}' ({}--help lists them)", where, word,
                     pathOf(app).empty() ? std::string() : pathOf(app) + " ");
}

}  // namespace

std::string nearestWord(const std::string& word, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const auto& candidate : known) {
    const std::size_t distance = editDistance(word, candidate);
    if (distance < best_distance) std::tie(best, best_distance) = std::make_tuple(candidate, distance);
  }
  // Near enough to be a slip: at most 2 edits, and at most a third of the word.
  const std::size_t stem = word.size() - std::min<std::size_t>(word.find_first_not_of('-'), word.size());
  return best_distance <= std::min<std::size_t>(2, std::max<std::size_t>(1, stem / 3)) ? best : std::string();
}

std::string usageMessage(CLI::App& app, const std::vector<std::string>& args, const std::string& cli11_message) {
  CLI::App* current = &app;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& word = args[i];
    if (word == "--") break;
    if (word.size() > 1 && word[0] == '-') {
      const std::string name = word.substr(0, word.find('='));
      const auto* option = optionNamed(current, name);
      if (option == nullptr) {
        const bool short_group = name[1] != '-' && name.size() > 2;  // "-qv"
        if (!short_group) return unknownOption(current, name);
        continue;
      }
      const bool takes_value = option->get_expected_max() > 0 && option->get_type_size_max() > 0;  // not a flag
      if (name.size() == word.size() && takes_value && i + 1 < args.size()) ++i;  // its value
      continue;
    }
    if (auto* command = subcommandNamed(current, word)) {
      current = command;
      continue;
    }
    if (current->get_require_subcommand_min() > 0) return unknownSubcommand(current, word);
  }
  if (current->get_require_subcommand_min() > 0 && cli11_message.find("subcommand") != std::string::npos) {
    return fmt::format("{} needs a subcommand: {}", pathOf(current).empty() ? "vsd-sumo" : pathOf(current),
                       fmt::join(subcommandNames(current), ", "));
  }
  std::string message = cli11_message;
  std::replace(message.begin(), message.end(), '\n', ' ');
  return pathOf(current).empty() ? message : pathOf(current) + ": " + message;
}

bool isUsageError(const ConfigError& error) {
  return std::string(error.what()).rfind("command line", 0) == 0;
}

std::vector<std::string> replaceDeprecatedSpellings(const CLI::App& app, std::vector<std::string>& args) {
  std::vector<std::string> notes;
  auto* current = const_cast<CLI::App*>(&app);  // only read: CLI11 lists subcommands through non-const calls
  for (auto& word : args) {
    if (word == "--") break;
    if (auto* command = subcommandNamed(current, word)) {
      current = command;
      continue;
    }
    if (word.size() < 2 || word[0] != '-') continue;
    const auto equals = word.find('=');
    const std::string name = word.substr(0, equals);
    for (const auto& rename : kRenames) {
      if (pathOf(current) != rename.command || name != rename.oldName) continue;
      notes.push_back(fmt::format("{} {} is deprecated; use {} (the old spelling still works for now)",
                                  rename.command, rename.oldName, rename.newName));
      word = rename.newName + (equals == std::string::npos ? std::string() : word.substr(equals));
    }
  }
  return notes;
}

}  // namespace vsd::cli
