#pragma once
// Logging goes to stderr through spdlog; stdout is reserved for results
// (summaries, tables) so that they can be piped.

#include <spdlog/spdlog.h>

#include <string>

namespace vsd {

enum class Verbosity { Quiet, Normal, Verbose };

/// Configures the process-wide logger and the progress display.
void configureLogging(Verbosity verbosity);

/// Version of this tool: "0.1.0+<commit>", "0.1.0+<commit>-dirty" when built from a tree with
/// uncommitted changes (taken at build time, core/provenance.hpp), "0.1.0" outside a checkout.
std::string toolVersion();

/// The current time in UTC, ISO 8601 ("2026-11-21T09:33:05Z"), for manifests and reports.
std::string utcTimestamp();

}  // namespace vsd
