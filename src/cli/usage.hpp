#pragma once
// Usage errors (docs/cli.md): a command line that does not parse ends with one line
// naming the unknown word and the nearest known one, and exit code 2; old spellings of
// renamed flags keep working with a one-line note.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "vsd/core/error.hpp"

namespace vsd::cli {

/// Exit code of a usage error (a runtime failure exits with 1).
constexpr int kUsageExit = 2;

/// The line to print for CLI11's parse error `cli11_message` on `args` (argv without the
/// program name): "unknown subcommand 'rnu' — did you mean 'run'?", "run: unknown option
/// '--sample' — did you mean '--samples'?", or CLI11's own message on one line.
std::string usageMessage(CLI::App& app, const std::vector<std::string>& args, const std::string& cli11_message);

/// Whether a ConfigError is about the command line itself (its message starts with
/// "command line" or with a flag, the convention of ConfigError::field("command line", ...)).
bool isUsageError(const ConfigError& error);

/// Rewrites old spellings of renamed flags in `args` (argv without the program name) to
/// the current ones; returns one deprecation note per rewritten flag.
std::vector<std::string> replaceDeprecatedSpellings(const CLI::App& app, std::vector<std::string>& args);

/// The word of `known` nearest to `word` by edit distance, or "" if none is near enough
/// to be what was meant.
std::string nearestWord(const std::string& word, const std::vector<std::string>& known);

}  // namespace vsd::cli
