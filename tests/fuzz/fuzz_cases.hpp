#pragma once
// Generators of fuzz cases, one per kind of input a user hands vsd-sumo: scenario
// YAMLs, dataset attributes and arrays, model descriptions and tensors, CLI flags,
// and faults (kills at write/rename points, misbehaving plugins).

#include <filesystem>
#include <string>
#include <vector>

#include "fuzz_support.hpp"

namespace vsd::fuzz {

/// Inputs every case starts from, built once per suite run (valid, small).
struct Fixtures {
  std::filesystem::path root;         ///< scratch folder of the suite
  std::filesystem::path run;          ///< run folder of scenarios/acc.yaml (dataset.h5, concrete.csv, ...)
  std::filesystem::path mapDataset;   ///< export of the OpenDRIVE test map (.h5)
  std::filesystem::path model;        ///< a tiny VectorNet trained on `run`
  std::filesystem::path checkpoint;   ///< its training state (<model>.last)
  std::filesystem::path openDrive;    ///< sumo_nets/opendrive_curve/curve.xodr
  std::filesystem::path routes;       ///< its demand
  std::filesystem::path xosc;         ///< acc sample 0 exported as OpenSCENARIO (+ its .xodr next to it)
  std::filesystem::path search;       ///< a finished small search of acc.yaml (seed 1), with .rounds/
  std::filesystem::path otherSearch;  ///< the same search with seed 2
  std::filesystem::path sweep;        ///< acc.yaml run as two shards (shards/shard-000K-of-0002), not merged
};

/// Builds the fixtures under `root` (throws std::runtime_error if one cannot be built).
Fixtures buildFixtures(const std::filesystem::path& root);

/// A case's own scratch folder under the suite's root.
std::filesystem::path caseFolder(const Fixtures& fixtures, const std::string& category, std::size_t index);

std::vector<Case> scenarioYamlCases(const Fixtures& fixtures, Random& random, std::size_t count);
std::vector<Case> datasetCases(const Fixtures& fixtures, Random& random, std::size_t count);
std::vector<Case> modelCases(const Fixtures& fixtures, Random& random, std::size_t count);
std::vector<Case> flagCases(const Fixtures& fixtures, Random& random, std::size_t count);
/// `run`, `export`, `train`, `predict` killed (SIGKILL) at one of their write/rename points.
std::vector<Case> killCases(const Fixtures& fixtures, Random& random, std::size_t count);
/// `run` with an Ego plugin that crashes, aborts, exits, hangs or fails (tests/plugins).
std::vector<Case> pluginCases(const Fixtures& fixtures, Random& random, std::size_t count);
/// Hostile inputs (issue 29), one class per case in turn: numbers of an .xosc, hostile
/// XML, special files, huge geometry, option injection, paths out of the file's folder,
/// foreign search checkpoints and round files, foreign or edited shards.
std::vector<Case> hostileInputCases(const Fixtures& fixtures, Random& random, std::size_t count);
/// Issue 29's reproductions of hostile .xosc numbers and XML, each exactly as reported
/// (a fixed list, whatever the count).
std::vector<Case> issueReproductionCases(const Fixtures& fixtures, Random& random, std::size_t count);

/// Problems of a dataset file (empty: it opens and validates).
std::string datasetProblems(const std::filesystem::path& path);

}  // namespace vsd::fuzz
