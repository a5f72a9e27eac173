#pragma once
// Results of an experiment (internal to the experiment module): the paper's
// findings checked on our ADE values, and the files under results/<name>/.

#include <string>
#include <vector>

#include "spec.hpp"
#include "vsd/core/files.hpp"
#include "vsd/experiment/experiment.hpp"

namespace vsd::experiment {

/// A cached artefact as the manifest lists it.
struct ArtefactRecord {
  std::string path;       ///< relative to the output folder
  std::string keyDigest;  ///< SHA-256 of its cache key
  bool reused = false;
};

/// Thresholds (m) behind the verdicts; README "Findings" quotes them.
inline constexpr double kGoodAde = 0.6;             ///< (a): the paper calls its 0.37-0.52 m good
inline constexpr double kGeneralisesAde = 1.0;      ///< "generalises": at most this ...
inline constexpr double kGeneralisesFactor = 3.0;   ///< ... and at most this times the in-distribution ADE
inline constexpr double kFailsAde = 2.0;            ///< "does not generalise": at least this ...
inline constexpr double kFailsFactor = 5.0;         ///< ... and at least this times the in-distribution ADE

/// The paper's findings (a)-(d) and the claim of rows 5/6 (e), decided from the main
/// model's ADE rows 1-6, 9 and 10 (means over seeds; rows missing or with another mix
/// give "not checked").
std::vector<Finding> checkFindings(const std::vector<AdeRow>& rows);

/// Stages ade.md/.csv, mae.md/.csv, findings.md in `folder` and commits it with
/// the manifest (written last, with every result file's hash and size).
void writeResults(const Spec& spec, const ExperimentOptions& options, ExperimentSummary& summary,
                  const std::vector<ArtefactRecord>& artefacts, OutputFolder& folder);

}  // namespace vsd::experiment
