// Fixtures, scenario-YAML mutation and CLI-flag mutation.
#include "fuzz_cases.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <regex>
#include <stdexcept>
#include <tuple>

#include "vsd/core/error.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::fuzz {

namespace {

fs::path sourceDir() { return VSD_SOURCE_DIR; }

/// Runs vsd-sumo to build a fixture; throws if it fails.
void buildWith(const std::vector<std::string>& args, const fs::path& work) {
  std::vector<std::string> argv = {(fs::path(VSD_BINARY_DIR) / "vsd-sumo").string(), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  const auto result = runWatched(argv, work, std::chrono::seconds(300));
  if (!result.exited || result.exitCode != 0) {
    throw std::runtime_error(fmt::format("building a fixture failed (exit {}): {}", result.exitCode, result.stderrText));
  }
}

}  // namespace

Fixtures buildFixtures(const fs::path& root) {
  Fixtures f;
  f.root = root;
  f.run = root / "fixtures" / "acc";
  f.mapDataset = root / "fixtures" / "curve.h5";
  f.model = root / "fixtures" / "model.pt";
  f.checkpoint = root / "fixtures" / "model.pt.last";
  f.openDrive = sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.xodr";
  f.routes = sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.rou.xml";
  const fs::path work = root / "fixtures" / "work";
  buildWith({"run", (sourceDir() / "scenarios" / "acc.yaml").string(), "--samples", "24", "--out", f.run.string()},
            work);
  buildWith({"export", "--opendrive", f.openDrive.string(), "--routes", f.routes.string(), "--out",
             f.mapDataset.string(), "--end", "40"},
            work);
  buildWith({"train", "--data", f.run.string(), "--out", f.model.string(), "--steps", "8", "--batch", "8", "--hidden",
             "8", "--global-width", "8", "--decoder-hidden", "16", "--threads", "1"},
            work);
  const fs::path exported = root / "fixtures" / "xosc";
  buildWith({"scenario", "export", (sourceDir() / "scenarios" / "acc.yaml").string(), "--samples", "1", "--out",
             exported.string()},
            work);
  f.xosc = exported / "acc_000000.xosc";
  f.search = root / "fixtures" / "search";
  f.otherSearch = root / "fixtures" / "search-seed2";
  // Two rounds of the first search; the other's first round is all its cases need.
  for (const auto& [folder, seed, budget] : {std::tuple{f.search, "1", "20"}, std::tuple{f.otherSearch, "2", "10"}}) {
    buildWith({"search", (sourceDir() / "scenarios" / "acc.yaml").string(), "-c", "d_min < 8", "--surrogate", "random",
               "--budget", budget, "--initial", "10", "--round", "10", "--pool", "100", "--seed", seed, "--out",
               folder.string()},
              work);
  }
  f.sweep = root / "fixtures" / "sweep";
  for (const char* shard : {"0/2", "1/2"}) {
    buildWith({"run", (sourceDir() / "scenarios" / "acc.yaml").string(), "--samples", "8", "--batch", "4", "--shard",
               shard, "--out", f.sweep.string()},
              work);
  }
  return f;
}

fs::path caseFolder(const Fixtures& fixtures, const std::string& category, std::size_t index) {
  const fs::path folder = fixtures.root / category / fmt::format("{:04}", index);
  fs::create_directories(folder);
  return folder;
}

namespace {

/// A command's argument in a case: "@x" names x in the case's `folder`; others stay.
std::string inCaseFolder(const std::string& arg, const fs::path& folder) {
  return arg.rfind('@', 0) == 0 ? (folder / arg.substr(1)).string() : arg;
}

}  // namespace

std::string datasetProblems(const fs::path& path) {
  const auto validation = vector::validateDataset(vector::resolveDatasetPath(path));
  if (validation.ok()) return {};
  return fmt::format("{} is invalid: {}", path.string(), validation.problems.front());
}

/// A model file is complete if vsd-sumo evaluates with it (a training killed after an epoch
/// leaves the best model so far: complete, by design, so that --resume can continue).
std::string modelProblems(const fs::path& model, const fs::path& data) {
  const RunResult run = runWatched({(fs::path(VSD_BINARY_DIR) / "vsd-sumo").string(), "--quiet", "evaluate", "--model",
                                    model.string(), "--data", data.string(), "--threads", "1"},
                                   model.parent_path() / "model-check", std::chrono::seconds(120));
  if (run.exited && run.exitCode == 0) return {};
  return fmt::format("{} does not evaluate: {}", model.string(), run.stderrText);
}

// --- scenario YAML ---------------------------------------------------------------------------

namespace {

/// Every node of a YAML tree with the path that reaches it (map keys and list indices).
struct NodeRef {
  std::vector<std::string> path;
  bool scalar = false;
};

void collectNodes(const YAML::Node& node, std::vector<std::string>& path, std::vector<NodeRef>& out) {
  out.push_back({path, node.IsScalar()});
  if (node.IsMap()) {
    for (const auto& entry : node) {
      path.push_back(entry.first.Scalar());
      collectNodes(entry.second, path, out);
      path.pop_back();
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      path.push_back("#" + std::to_string(i));
      collectNodes(node[i], path, out);
      path.pop_back();
    }
  }
}

/// The node at `path` (yaml-cpp nodes are handles: assigning to the result edits the tree).
YAML::Node nodeAt(YAML::Node root, const std::vector<std::string>& path, std::size_t length) {
  YAML::Node node = root;
  for (std::size_t i = 0; i < length; ++i) {
    const auto& key = path[i];
    node.reset(key[0] == '#' ? node[std::stoul(key.substr(1))] : node[key]);
  }
  return node;
}

/// Expressions that evaluate to something no road, speed or duration can be.
const std::vector<std::string>& hostileExpressions() {
  static const std::vector<std::string> values = {
      "1/0", "-1/0", "0/0", "sqrt(-1)", "1e308*10", "-v_ego", "v_ego/0", "x_co^100", "-1e6", "1e6", "ln(0)",
      "a0 +", "unknown_name", "[1, 2]", "{a: 1}"};
  return values;
}

std::string mutateYaml(const std::string& text, Random& random, std::string& description) {
  YAML::Node root = YAML::Load(text);
  std::vector<NodeRef> nodes;
  std::vector<std::string> path;
  collectNodes(root, path, nodes);
  const NodeRef& target = nodes[1 + random.index(nodes.size() - 1)];  // never the root itself
  YAML::Node parent = nodeAt(root, target.path, target.path.size() - 1);
  const std::string& key = target.path.back();
  const std::string where = fmt::format("{}", fmt::join(target.path, "."));
  const int operation = static_cast<int>(random.index(5));
  if (operation == 0 && parent.IsMap()) {
    parent.remove(key);
    description = "removed " + where;
  } else if (operation == 1) {
    const auto& value = random.pick(hostileNumbers());
    nodeAt(root, target.path, target.path.size()) = value;
    description = fmt::format("{} = '{}'", where, value);
  } else if (operation == 2) {
    const auto& value = random.pick(hostileExpressions());
    nodeAt(root, target.path, target.path.size()) = YAML::Load(value);
    description = fmt::format("{} = {}", where, value);
  } else if (operation == 3) {
    YAML::Node replacement = random.chance(0.5) ? YAML::Load("[]") : YAML::Load("{}");
    nodeAt(root, target.path, target.path.size()) = replacement;
    description = fmt::format("{} = empty list/map", where);
  } else {
    // Numbers scaled to absurd sizes, in place (keeps the file otherwise plausible).
    YAML::Node node = nodeAt(root, target.path, target.path.size());
    double value = 0.0;
    if (node.IsScalar() && YAML::convert<double>::decode(node, value)) {
      const double factor = random.pick(std::vector<double>{-1.0, 0.0, 1e-9, 1e3, 1e9, 1e300});
      node = fmt::format("{}", value * factor);
      description = fmt::format("{} x {}", where, factor);
    } else {
      node = "nonsense";
      description = where + " = nonsense";
    }
  }
  YAML::Emitter emitter;
  emitter << root;
  return emitter.c_str();
}

}  // namespace

std::vector<Case> scenarioYamlCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  const std::vector<std::string> scenarios = {"acc.yaml", "lk.yaml", "acc_lk.yaml"};
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    const fs::path folder = caseFolder(fixtures, "yaml", i);
    const std::string name = random.pick(scenarios);
    std::ifstream stream(sourceDir() / "scenarios" / name);
    const std::string text((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
    std::string description;
    const std::string mutated = mutateYaml(text, random, description);
    const fs::path file = folder / name;
    std::ofstream(file) << mutated;
    Case c;
    c.name = fmt::format("yaml/{}: {}", name, description);
    const fs::path out = folder / "out";
    c.args = {"run", file.string(), "--samples", "3", "--out", out.string()};
    c.outputs = {out};
    c.checkOutputs = [out] {
      for (const char* output : {"concrete.csv", "traces.h5", "dataset.h5", "manifest.json"}) {
        if (!fs::exists(out / output)) return fmt::format("{} is missing", (out / output).string());
      }
      return datasetProblems(out / "dataset.h5");
    };
    cases.push_back(std::move(c));
  }
  return cases;
}

// --- CLI flags -------------------------------------------------------------------------------

namespace {

/// A valid command and the output it promises; flags are mutated one at a time.
struct BaseCommand {
  std::string name;
  std::vector<std::string> args;  ///< "@x": x in the case folder
  std::vector<std::string> numericFlags;
  fs::path output;  ///< relative to the case folder
  bool validatesDataset = false;
};

std::vector<BaseCommand> baseCommands(const Fixtures& f) {
  const std::string model = f.model.string();
  const std::string run = f.run.string();
  return {
      {"run",
       {"run", (sourceDir() / "scenarios" / "acc.yaml").string(), "--samples", "3", "--out", "@out"},
       {"--samples", "--seed", "--jobs", "--batch", "--first-sample", "--compression"},
       "out",
       true},
      {"export",
       {"export", "--opendrive", f.openDrive.string(), "--routes", f.routes.string(), "--end", "25", "--out", "@out.h5"},
       {"--seed", "--step", "--horizon", "--history", "--stride", "--radius", "--max-vector-length", "--begin", "--end",
        "--max-samples", "--lane-change-duration", "--compression"},
       "out.h5",
       true},
      {"train",
       {"train", "--data", run, "--out", "@m.pt", "--steps", "3", "--batch", "8", "--hidden", "8", "--global-width", "8",
        "--decoder-hidden", "16", "--threads", "1"},
       {"--seed", "--threads", "--steps", "--patience", "--batch", "--lr", "--weight-decay", "--validation-fraction",
        "--hidden", "--layers", "--global-width", "--heads", "--decoder-hidden"},
       "m.pt"},
      {"predict", {"predict", "--model", model, "--data", run, "--out", "@p.h5"}, {"--threads"}, "p.h5"},
      {"evaluate", {"evaluate", "--model", model, "--data", run, "--csv", "@e.csv"}, {"--threads"}, "e.csv"},
      {"compare",
       {"compare", "--model", model, "--data", run, "--out", "@report"},
       {"--samples", "--seed", "--jobs", "--threads", "--worst"},
       "report"},
      {"compare-scenario",
       {"compare", (sourceDir() / "scenarios" / "acc.yaml").string(), "--model", model, "--samples", "4", "--out",
        "@report"},
       {"--samples", "--seed", "--jobs", "--threads", "--worst"},
       "report"},
      {"show", {"dataset", "show", run, "--svg", "@s.svg"}, {"--sample"}, "s.svg"},
      {"baseline",
       {"baseline", "--data", run, "--test", run, "--targets", "a_min", "--trees", "5", "--bnn-epochs", "2", "--out",
        "@b.csv"},
       {"--train-rows", "--trees", "--max-features", "--min-samples-split", "--bnn-hidden", "--bnn-epochs",
        "--bnn-samples", "--seed"},
       "b.csv"},
  };
}

}  // namespace

std::vector<Case> flagCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  const auto commands = baseCommands(fixtures);
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    const fs::path folder = caseFolder(fixtures, "flags", i);
    const BaseCommand& base = random.pick(commands);
    const std::string& flag = random.pick(base.numericFlags);
    const std::string& value = random.pick(hostileNumbers());
    Case c;
    c.name = fmt::format("flags/{} {} '{}'", base.name, flag, value);
    const fs::path output = folder / base.output;
    for (std::size_t a = 0; a < base.args.size(); ++a) {
      if (base.args[a] == flag) {  // the base's own value of this flag is replaced
        ++a;
        continue;
      }
      c.args.push_back(inCaseFolder(base.args[a], folder));
    }
    // "--flag=value" keeps a value such as "-1" a value.
    c.args.push_back(flag + "=" + value);
    c.outputs = {output};
    if (base.validatesDataset) {
      c.checkOutputs = [output] {
        return datasetProblems(fs::is_directory(output) ? output / "dataset.h5" : output);
      };
    }
    cases.push_back(std::move(c));
  }
  return cases;
}

// --- kills at write/rename points ------------------------------------------------------------

namespace {

/// A command that writes, its write/rename points (vsd/core/fault.hpp) and an older
/// output to start from (empty: none).
struct Writer {
  std::string name;
  std::vector<std::string> args;  ///< "@x": x in the case folder
  std::string output;
  std::vector<std::string> points;
  fs::path older;
  bool validatesDataset = false;
  bool evaluatesModel = false;
};

std::vector<Writer> writers(const Fixtures& f) {
  const std::vector<std::string> atomic = {"atomic.fsync:*", "atomic.rename:*"};
  return {
      {"run",
       {"run", (sourceDir() / "scenarios" / "acc.yaml").string(), "--samples", "3", "--batch", "2", "--out", "@out"},
       "out",
       {"run.write", "folder.stage:*", "folder.fsync:*", "folder.manifest", "folder.decide", "folder.unlink-manifest",
        "folder.remove:*", "folder.rename:*", "folder.publish", "folder.cleanup"},
       f.run,
       true},
      {"export",
       {"export", "--opendrive", f.openDrive.string(), "--routes", f.routes.string(), "--end", "25", "--out", "@out.h5"},
       "out.h5",
       atomic,
       f.mapDataset,
       true},
      {"train",
       {"train", "--data", f.run.string(), "--out", "@m.pt", "--steps", "3", "--batch", "8", "--hidden", "8",
        "--global-width", "8", "--decoder-hidden", "16", "--threads", "1"},
       "m.pt",
       atomic,
       f.model,
       false,
       true},
      {"predict",
       {"predict", "--model", f.model.string(), "--data", f.run.string(), "--out", "@p.h5", "--threads", "1"},
       "p.h5",
       atomic,
       {}},
  };
}

}  // namespace

std::vector<Case> killCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  const auto commands = writers(fixtures);
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    const fs::path folder = caseFolder(fixtures, "kills", i);
    // Round robin over the commands, so that even a short run kills each of them.
    const Writer& writer = commands[i % commands.size()];
    const std::string point = random.pick(writer.points) + (random.chance(0.3) ? "#2" : "");
    const fs::path output = folder / writer.output;
    const bool older = !writer.older.empty() && random.chance(0.6);
    if (older) fs::copy(writer.older, output, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    Case c;
    c.name = fmt::format("kills/{} killed at {}{}", writer.name, point, older ? " (over an older output)" : "");
    for (const auto& arg : writer.args) c.args.push_back(inCaseFolder(arg, folder));
    c.outputs = {output};
    c.environment = {"VSD_FAULT=kill@" + point};
    c.expectKill = true;
    if (writer.validatesDataset) c.checkOutputs = [output] { return datasetProblems(output); };
    if (writer.evaluatesModel) c.checkOutputs = [output, data = fixtures.run] { return modelProblems(output, data); };
    cases.push_back(std::move(c));
  }
  return cases;
}

// --- misbehaving Ego plugins -----------------------------------------------------------------

std::vector<Case> pluginCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  const std::vector<std::string> controllers = {"crashing_ego", "aborting_ego", "exiting_ego",
                                                "hanging_ego",  "failing_ego",  "misbehaving_ego"};
  const fs::path plugin = fs::path(VSD_BINARY_DIR) / "plugins" / "libvsd_misbehaving_egos.so";
  std::ifstream stream(sourceDir() / "scenarios" / "acc_lk.yaml");
  const std::string text((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  const std::regex controller_entry(R"(name: paper_ego[^\n]*\n(\s*)params: \{[^}]*\})");
  if (!std::regex_search(text, controller_entry)) throw std::runtime_error("acc_lk.yaml: no paper_ego controller entry");
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    const fs::path folder = caseFolder(fixtures, "plugins", i);
    const std::string& controller = controllers[i % controllers.size()];
    const std::string fault = random.pick(std::vector<std::string>{"1", "v_ego > 12", "v_ego > 14"});
    const std::string at = random.pick(std::vector<std::string>{"-1", "0", "1.0"});
    std::string params = fmt::format("fault: {}, at: {}", fault, at);
    if (controller == "misbehaving_ego") params += ", kind: (v_ego > 12) + (v_ego > 13) + (v_ego > 14) + (v_ego > 14.4)";
    const std::string scenario = std::regex_replace(
        text, controller_entry, fmt::format("name: {}\n$1library: {}\n$1params: {{{}}}", controller, plugin.string(), params));
    const fs::path file = folder / "acc_lk.yaml";
    std::ofstream(file) << scenario;
    const std::string jobs = random.chance(0.5) ? "1" : "2";
    const std::string batch = random.chance(0.5) ? "1" : "3";
    const fs::path out = folder / "out";
    Case c;
    c.name = fmt::format("plugins/{} ({}) --jobs {} --batch {}", controller, params, jobs, batch);
    c.args = {"run", file.string(), "--samples", "3", "--jobs", jobs, "--batch", batch, "--step-timeout", "1",
              "--out", out.string()};
    c.outputs = {out};
    c.checkOutputs = [out] { return datasetProblems(out); };
    cases.push_back(std::move(c));
  }
  return cases;
}

}  // namespace vsd::fuzz
