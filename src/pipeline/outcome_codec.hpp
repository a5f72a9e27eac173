#pragma once
// Binary encoding of scenario outcomes for the pipe between worker processes
// and the parent (same binary on both ends). Private to the pipeline: others measure it
// through passThroughWorkerPipe() (run.hpp).

#include <vector>

#include "vsd/pipeline/run.hpp"

namespace vsd::pipeline {

std::vector<char> encodeOutcomes(const std::vector<ScenarioOutcome>& outcomes);
std::vector<ScenarioOutcome> decodeOutcomes(const std::vector<char>& bytes);

}  // namespace vsd::pipeline
