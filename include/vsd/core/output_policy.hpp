#pragma once
// One policy for every output a command writes (docs/output-policy.md). Before any
// work starts, checkOutput() looks at what is at the output path:
//
//   nothing                                     -> written
//   the same kind of vsd-sumo output, about the
//   same subject (scenario, model, spec, ...)   -> replaced (a re-run)
//   the same kind, about another subject        -> replaced only with --force
//   anything else: a file or folder vsd-sumo did
//   not write, an output of another kind, a file
//   that belongs to an output folder, or an input
//   of the same command                         -> refused, --force or not
//
// A folder's files that no manifest lists (a user's notes) are never replaced; a
// file of a name the folder's kind writes that no manifest lists is the user's and
// makes the folder refused (OutputFolder::commit checks the same at the end, for
// every writer of a folder). Resuming (search, the experiment's cache) happens only
// where a command documents it, after this check passed.
//
// A kind says how to recognise an existing output of it and what that output is about;
// kinds whose format core can read are here (folders by their manifest.json, datasets
// and predictions by their HDF5 schema, tables by their CSV header, drawings and
// OpenSCENARIO distributions by their text); a layer that reads a format better may
// copy a kind and give it a sharper `identify` (the model file's training labels).
// Every message has the same wording (messages are built here only).

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vsd {

/// A kind of output.
struct OutputKind {
  std::string noun;     ///< "run folder", "model file": messages say "a <noun>"
  bool folder = false;  ///< a folder with a manifest.json (OutputFolder) or a single file
  /// Folders: entries (relative names) it writes; such an entry that no manifest lists is a user's file.
  std::vector<std::string> writes;
  /// Given an existing path: nullopt if it is not an output of this kind; else what it is
  /// about ("" when the output records nothing about its subject). Never throws.
  std::function<std::optional<std::string>(const std::filesystem::path&)> identify;
};

/// The kinds core can recognise (one entry each).
namespace output_kinds {
const OutputKind& runFolder();          ///< run, merge: concrete.csv, traces.h5, dataset.h5; subject: functional scenario
const OutputKind& searchFolder();       ///< search; subject: "<functional scenario>: <criterion as given>"
const OutputKind& comparisonFolder();   ///< compare; subject: "<scenario or data> with <model>"
const OutputKind& deviationsFolder();   ///< deviations; subject: "<data> with <model>"
const OutputKind& searchBenchmarkFolder();  ///< bench search --out; subject: "<scenario file>: <criterion>"
const OutputKind& experimentFolder();   ///< experiment; subject: the spec's name
const OutputKind& scenarioExportFolder();  ///< scenario export; subject: functional scenario
const OutputKind& datasetFile();        ///< export; HDF5 vsd-dataset/*; subject: its labels
const OutputKind& predictionsFile();    ///< predict; HDF5 vsd-predictions/*; subject: "<model> on <dataset file>"
/// train; a torch archive holding a vsd-sumo model description; subject: "" (vsd-sumo-ml
/// copies it with the training labels as subject).
const OutputKind& modelFile();
const OutputKind& distributionFile();   ///< scenario distribution; an OpenSCENARIO ParameterValueDistribution
const OutputKind& sceneDrawing();       ///< dataset show --svg; an SVG drawing as vsd-sumo writes them
/// Every kind above, for naming what an existing output is.
const std::vector<const OutputKind*>& all();
}  // namespace output_kinds

/// A kind of text file recognised by how it starts: a CSV table by its header line, an
/// HTML report by its head (its subject is ""; such files record nothing about what made
/// them). E.g. textFileKind("evaluation table", "label,samples,ade_m").
OutputKind textFileKind(const std::string& noun, const std::string& start);

struct OutputRequest {
  std::filesystem::path path;
  const OutputKind* kind = nullptr;
  std::string subject;                ///< what the new output is about (compared with the existing one's)
  bool force = false;                 ///< replace an output of the same kind about another subject
  std::string flag = "--out";         ///< the flag that named the path, for messages
  std::string forceFlag = "--force";  ///< how to ask for the replacement
  /// The command's inputs (flag, path): the output may be none of them.
  std::vector<std::pair<std::string, std::filesystem::path>> inputs;
};

enum class OutputStatus {
  New,           ///< nothing at the path (or an empty folder)
  Replace,       ///< an output of the same kind about the same subject
  ForcedReplace  ///< an output of the same kind about another subject, and force was given
};

/// Applies the policy above. Throws ConfigError (one line: flag, path, what is there and
/// what to do) when the output may not be written. Reads only.
OutputStatus checkOutput(const OutputRequest& request);

/// Throws ConfigError if `relative` (a name the writer is about to put in `folder`) is not
/// among `listed`, the names the folder's manifest lists: the file there is the user's.
/// OutputFolder::commit's last check; `flag` ("--out", or "") starts the message.
void refuseUnlistedFile(const std::filesystem::path& folder, const std::string& relative,
                        const std::vector<std::string>& listed, const std::string& flag);

}  // namespace vsd
