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
/// give "not checked"), when the spec has the paper's table rows; then, with a
/// leave_one_out section, one finding per held-out functional scenario (held_out.cpp).
std::vector<Finding> checkFindings(const Spec& spec, const std::vector<AdeRow>& rows);
std::vector<Finding> checkFindings(const std::vector<AdeRow>& rows);

/// Per held-out functional scenario: do its few own samples added to the other scenarios'
/// data predict it no worse than all its own samples alone (the paper's rows 9 and 10)?
std::vector<Finding> heldOutFindings(const Spec& spec, const std::vector<AdeRow>& main_rows);

/// held_out.csv (long format) and held_out.md (ADE and metric tables per held-out scenario).
std::pair<std::string, std::string> heldOutFiles(const Spec& spec, const ExperimentSummary& summary);

// Formatting shared by the result files.
double adeOf(const AdeRow& row, const std::string& label);        ///< NaN where the row has no such label
std::string metres(double value);                                 ///< "0.57", "–" for NaN
std::string adeText(const AdeRow& row, const std::string& label);  ///< "0.57" or "0.57 ± 0.03" over seeds
std::string mixText(const AdeRow& row);                           ///< "acc 2000 + lk 200"
std::string percent(double share);                                ///< "51 %"
std::string coverageText(double share, std::size_t scenes);       ///< "51 % (48–54)": with its Wilson 95 % interval
std::string sizesLine(const Spec& spec);                          ///< the data and training sizes, one paragraph
std::string modelDescription(const ModelSpec& model);             ///< "kinematic (accel_weight=10), lane frame"

/// Stages ade.md/.csv, mae.md/.csv, findings.md in `folder` and commits it with
/// the manifest (written last, with every result file's hash and size).
void writeResults(const Spec& spec, const ExperimentOptions& options, ExperimentSummary& summary,
                  const std::vector<ArtefactRecord>& artefacts, OutputFolder& folder);

}  // namespace vsd::experiment
