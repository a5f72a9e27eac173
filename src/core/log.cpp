#include "vsd/core/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <ctime>

#include "vsd/core/progress.hpp"
#include "vsd/core/provenance.hpp"

#ifndef VSD_VERSION
#define VSD_VERSION "unknown"
#endif

namespace vsd {

void configureLogging(Verbosity verbosity) {
  auto logger = spdlog::stderr_color_mt("vsd");
  logger->set_pattern("%^%l%$: %v");
  switch (verbosity) {
    case Verbosity::Quiet:
      logger->set_level(spdlog::level::warn);
      Progress::setEnabled(false);
      break;
    case Verbosity::Normal:
      logger->set_level(spdlog::level::info);
      break;
    case Verbosity::Verbose:
      logger->set_level(spdlog::level::debug);
      break;
  }
  spdlog::set_default_logger(logger);
}

std::string toolVersion() {
  const auto built = buildProvenance();
  if (built.commit.empty()) return VSD_VERSION;
  return fmt::format("{}+{}{}", VSD_VERSION, built.commit, built.dirty ? "-dirty" : "");
}

std::string utcTimestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buffer;
}

}  // namespace vsd
