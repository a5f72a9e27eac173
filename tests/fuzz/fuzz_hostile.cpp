// Hostile inputs (issue 29): files that try to make vsd-sumo do something — hostile
// XML, special files, huge geometry, options for SUMO that name files, paths out of the
// file's folder, foreign or edited checkpoints, round files and shards. Each case runs
// one command; the oracle (fuzz_support.hpp) requires one line and exit 1 or a valid
// result, and that the paths the file aimed at stay untouched (they are the case's
// outputs: a fresh path must stay absent).
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include <fstream>
#include <stdexcept>
#include <regex>
#include <sstream>

#include "fuzz_cases.hpp"

namespace fs = std::filesystem;

namespace vsd::fuzz {

namespace {

fs::path sourceDir() { return VSD_SOURCE_DIR; }

fs::path fixturesRoot(const Fixtures& f) { return f.root; }

std::string textOf(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
}

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

/// Writes a mutation of the file at `path`; a mutation that changed nothing would test
/// nothing (a pattern that no longer matches the exporter's output), so it stops the suite.
void writeMutation(const fs::path& path, const std::string& text) {
  if (text == textOf(path)) throw std::runtime_error("fuzz: a mutation of " + path.string() + " changed nothing");
  writeText(path, text);
}

/// Replaces the first match of `pattern` in `text` by `replacement` (regex syntax).
std::string replaceFirst(const std::string& text, const std::string& pattern, const std::string& replacement) {
  return std::regex_replace(text, std::regex(pattern), replacement, std::regex_constants::format_first_only);
}

/// The exported scenario copied into `folder` (acc_000000.xosc + .xodr); returns the .xosc.
fs::path copyScenario(const Fixtures& f, const fs::path& folder) {
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(f.xosc.parent_path())) {
    if (entry.path().extension() == ".xosc" || entry.path().extension() == ".xodr") {
      fs::copy_file(entry.path(), folder / entry.path().filename(), fs::copy_options::overwrite_existing);
    }
  }
  return folder / f.xosc.filename();
}

std::string withProperty(const std::string& xosc, const std::string& name, const std::string& value) {
  return replaceFirst(xosc, "name=\"" + std::regex_replace(name, std::regex("\\."), "\\.") + "\" value=\"[^\"]*\"",
                      "name=\"" + name + "\" value=\"" + value + "\"");
}

/// `run FILE.xosc` into the case folder's out/, whose result must validate if it succeeds.
Case runXosc(const fs::path& xosc, const fs::path& folder, const std::string& name) {
  Case c;
  c.name = name;
  const fs::path out = folder / "out";
  c.args = {"run", xosc.string(), "--out", out.string()};
  c.outputs = {out};
  c.checkOutputs = [out] { return datasetProblems(out / "dataset.h5"); };
  return c;
}

// --- one generator per class of hostile input ------------------------------------------------

/// A number of the .xosc (an attribute or a FileHeader property) set to `value`; `target`
/// names which (empty: one drawn from `random`).
Case xoscNumberCaseWith(const Fixtures& f, Random& random, const fs::path& folder, const std::string& target_name,
                        const std::string& value) {
  const fs::path xosc = copyScenario(f, folder);
  std::string text = textOf(xosc);
  struct Target {
    std::string what;
    std::function<std::string(const std::string&)> apply;
  };
  const std::vector<Target> targets = {
      {"vehicle length", [&](const std::string& t) { return replaceFirst(t, "length=\"[^\"]*\"", "length=\"" + value + "\""); }},
      {"vehicle width", [&](const std::string& t) { return replaceFirst(t, " width=\"[^\"]*\"", " width=\"" + value + "\""); }},
      {"Performance maxSpeed", [&](const std::string& t) { return replaceFirst(t, "maxSpeed=\"[^\"]*\"", "maxSpeed=\"" + value + "\""); }},
      {"Performance maxDeceleration", [&](const std::string& t) { return replaceFirst(t, "maxDeceleration=\"[^\"]*\"", "maxDeceleration=\"" + value + "\""); }},
      {"vsd-sumo.seed", [&](const std::string& t) { return withProperty(t, "vsd-sumo.seed", value); }},
      {"vsd-sumo.sample", [&](const std::string& t) { return withProperty(t, "vsd-sumo.sample", value); }},
      {"vsd-sumo.step", [&](const std::string& t) { return withProperty(t, "vsd-sumo.step", value); }},
      {"vsd-sumo.road.x_range", [&](const std::string& t) { return withProperty(t, "vsd-sumo.road.x_range", value + " 55"); }},
      {"vsd-sumo.road.extension", [&](const std::string& t) { return withProperty(t, "vsd-sumo.road.extension", "30 " + value); }},
      {"StopTrigger time", [&](const std::string& t) {
         const auto stop = t.find("<StopTrigger");
         return t.substr(0, stop) + replaceFirst(t.substr(stop), "value=\"[^\"]*\"", "value=\"" + value + "\"");
       }},
      {"collision action", [&](const std::string& t) {
         return withProperty(t, "vsd-sumo.sumo.collision_action", value);
       }},
  };
  const Target* target = &random.pick(targets);
  for (const auto& candidate : targets) {
    if (candidate.what == target_name) target = &candidate;
  }
  writeText(xosc, target->apply(text));  // a hostile number may equal the original
  return runXosc(xosc, folder, fmt::format("hostile/xosc-number: {} = '{}'", target->what, value));
}

Case xoscNumberCase(const Fixtures& f, Random& random, const fs::path& folder) {
  std::string value = random.pick(hostileNumbers());
  Case drawn = xoscNumberCaseWith(f, random, folder, "", value);
  if (drawn.name.find("collision action") != std::string::npos) {  // a name, not a number
    value = random.pick(std::vector<std::string>{"explode", "", "none"});
    fs::remove_all(folder);
    drawn = xoscNumberCaseWith(f, random, folder, "collision action", value);
  }
  return drawn;
}

/// Hostile XML of `kind`: 0 entity expansion, 1 an external entity, 2 deep nesting, 3 a
/// cut-off file.
Case hostileXmlCaseOfKind(const Fixtures& f, Random& random, const fs::path& folder, int kind) {
  const fs::path xosc = copyScenario(f, folder);
  std::string text = textOf(xosc);
  const auto root = text.find("<OpenSCENARIO");
  std::string what;
  if (kind == 0) {
    std::string doctype = "<!DOCTYPE OpenSCENARIO [\n  <!ENTITY a0 \"lol\">\n";
    for (int i = 1; i <= 9; ++i) {
      std::string tenfold;
      for (int k = 0; k < 10; ++k) tenfold += fmt::format("&a{};", i - 1);
      doctype += fmt::format("  <!ENTITY a{} \"{}\">\n", i, tenfold);
    }
    doctype += "]>\n";
    text.insert(root, doctype);
    text = replaceFirst(text, "name=\"vsd-sumo.functional_scenario\" value=\"[^\"]*\"", "name=\"vsd-sumo.functional_scenario\" value=\"&a9;\"");
    what = "billion laughs";
  } else if (kind == 1) {
    text.insert(root, "<!DOCTYPE OpenSCENARIO [ <!ENTITY xxe SYSTEM \"file:///etc/passwd\"> ]>\n");
    text = replaceFirst(text, "name=\"vsd-sumo.seed\" value=\"[^\"]*\"", "name=\"vsd-sumo.seed\" value=\"&xxe;\"");
    what = "external entity (XXE)";
  } else if (kind == 2) {
    std::string deep;
    for (int i = 0; i < 200000; ++i) deep += "<Properties>";
    text = replaceFirst(text, "<Properties>", deep);
    what = "200,000 nested elements";
  } else {
    text = text.substr(0, random.index(text.size()));
    what = "cut short";
  }
  writeMutation(xosc, text);
  Case c = runXosc(xosc, folder, "hostile/xml: " + what);
  // Entity declarations are refused (issue 24) and the unclosed nesting is not well-formed;
  // a file cut after its last element (only the final newline gone) may still run.
  c.mustRefuse = kind != 3;
  return c;
}

Case hostileXmlCase(const Fixtures& f, Random& random, const fs::path& folder) {
  const int kind = static_cast<int>(random.index(4));
  return hostileXmlCaseOfKind(f, random, folder, kind);
}

/// Special files where a file is expected: devices and FIFOs, as the scenario or as the road.
Case specialFileCase(const Fixtures& f, Random& random, const fs::path& folder) {
  fs::create_directories(folder);
  const fs::path fifo = folder / "pipe.xodr";
  ::mkfifo(fifo.c_str(), 0600);
  const int kind = static_cast<int>(random.index(4));
  if (kind == 0) {
    Case c;
    c.mustRefuse = true;
    c.name = "hostile/special: run /dev/zero";
    c.args = {"run", "/dev/zero", "--out", (folder / "out").string()};
    c.outputs = {folder / "out"};
    return c;
  }
  if (kind == 1) {
    const fs::path yaml_fifo = folder / "scenario.yaml";
    ::mkfifo(yaml_fifo.c_str(), 0600);
    Case c;
    c.mustRefuse = true;
    c.name = "hostile/special: run a FIFO as the scenario";
    c.args = {"run", yaml_fifo.string(), "--out", (folder / "out").string()};
    c.outputs = {folder / "out"};
    return c;
  }
  const fs::path xosc = copyScenario(f, folder);
  const std::string road = kind == 2 ? std::string("/dev/zero") : fifo.filename().string();
  writeMutation(xosc, replaceFirst(textOf(xosc), "filepath=\"[^\"]*\"", "filepath=\"" + road + "\""));
  Case c = runXosc(xosc, folder, "hostile/special: LogicFile " + road);
  c.mustRefuse = true;
  return c;
}

/// OpenDRIVE geometry of absurd size: lengths, curvature, point counts.
Case geometryCase(const Fixtures& f, Random& random, const fs::path& folder) {
  const fs::path xosc = copyScenario(f, folder);
  const fs::path xodr = fs::path(xosc).replace_extension(".xodr");
  std::string text = textOf(xodr);
  const int kind = static_cast<int>(random.index(4));
  std::string what;
  const auto last_geometry = text.rfind("<geometry ");
  const auto end = text.find("</geometry>", last_geometry) + std::string("</geometry>").size();
  const std::string geometry = text.substr(last_geometry, end - last_geometry);
  if (kind <= 1) {
    const std::string length = kind == 0 ? "1e9" : "100000";
    std::string arc = replaceFirst(geometry, "length=\"[^\"]*\"", "length=\"" + length + "\"");
    arc = replaceFirst(arc, "<line ?/>", "<arc curvature=\"0.001\"/>");
    text.replace(last_geometry, end - last_geometry, arc);
    what = "an arc of " + length + " m";
  } else if (kind == 2) {
    std::string arc = replaceFirst(geometry, "<line ?/>", "<arc curvature=\"1e9\"/>");
    text.replace(last_geometry, end - last_geometry, arc);
    what = "curvature 1e9";
  } else {
    std::string many;
    for (int i = 0; i < 100001; ++i) many += geometry;
    text.replace(last_geometry, end - last_geometry, many);
    what = "100,001 geometries";
  }
  writeMutation(xodr, text);
  Case c = runXosc(xosc, folder, "hostile/geometry: " + what);
  c.mustRefuse = true;
  return c;
}

/// Options for SUMO and netconvert that would write files (a victim path must stay absent).
Case optionInjectionCase(const Fixtures& f, Random& random, const fs::path& folder) {
  fs::create_directories(folder);
  const fs::path victim = folder / "victim.xml";
  const int kind = static_cast<int>(random.index(3));
  if (kind == 2) {
    const fs::path yaml = folder / "acc.yaml";
    writeText(yaml, textOf(sourceDir() / "scenarios" / "acc.yaml") +
                        fmt::format("\nsumo:\n  sumo_options: [\"--fcd-output\", \"{}\"]\n", victim.string()));
    Case c;
    c.name = "hostile/options: YAML sumo_options --fcd-output";
    c.args = {"run", yaml.string(), "--samples", "2", "--out", (folder / "out").string()};
    c.outputs = {folder / "out"};
    c.untouched = {victim};
    c.mustRefuse = true;
    return c;
  }
  const fs::path xosc = copyScenario(f, folder);
  const std::string property = kind == 0 ? "vsd-sumo.sumo.options" : "vsd-sumo.sumo.netconvert_options";
  const std::string option = kind == 0 ? "--fcd-output" : "--plain-output-prefix";
  const std::string json = nlohmann::json(std::vector<std::string>{option, victim.string()}).dump();
  std::string escaped = std::regex_replace(json, std::regex("\""), "&quot;");
  writeMutation(xosc, withProperty(textOf(xosc), property, escaped));
  Case c = runXosc(xosc, folder, fmt::format("hostile/options: {} {}", property, option));
  c.untouched = {victim};
  for (const char* suffix : {".nod.xml", ".edg.xml", ".con.xml", ".tll.xml"}) c.untouched.emplace_back(victim.string() + suffix);
  c.mustRefuse = true;
  return c;
}

/// Paths out of the file's folder: the road, a plugin, an experiment's results folder.
Case traversalCase(const Fixtures& f, Random& random, const fs::path& folder) {
  const fs::path inner = folder / "inner";
  const fs::path xosc = copyScenario(f, inner);
  const int kind = static_cast<int>(random.index(3));
  if (kind == 0) {
    fs::copy_file(fs::path(xosc).replace_extension(".xodr"), folder / "outside.xodr");
    writeMutation(xosc, replaceFirst(textOf(xosc), "filepath=\"[^\"]*\"", "filepath=\"../outside.xodr\""));
    Case c = runXosc(xosc, inner, "hostile/traversal: LogicFile ../outside.xodr");
    c.mustRefuse = true;
    return c;
  }
  if (kind == 1) {
    const std::string library = "<Property name=\"vsd-sumo.library\" value=\"../../../lib/libc.so.6\"/>";
    // Into the Ego's controller (its first parameter), where a plugin is named.
    writeMutation(xosc, replaceFirst(textOf(xosc), "<Property name=\"time_gap\"", library + "<Property name=\"time_gap\""));
    Case c = runXosc(xosc, inner, "hostile/traversal: controller library ../../../lib/libc.so.6");
    c.mustRefuse = true;
    return c;
  }
  const fs::path spec = inner / "spec.yaml";
  std::string text = textOf(sourceDir() / "scenarios" / "experiments" / "paper.yaml");
  text = replaceFirst(text, "\nname: paper", "\nname: ../../escaped");
  text = std::regex_replace(text, std::regex("\\.\\./acc"), (sourceDir() / "scenarios" / "acc").string());
  text = std::regex_replace(text, std::regex("\\.\\./lk"), (sourceDir() / "scenarios" / "lk").string());
  writeText(spec, text);
  Case c;
  c.name = "hostile/traversal: experiment name ../../escaped";
  c.args = {"experiment", spec.string(), "--quick"};
  c.untouched = {folder / "escaped", folder / "results", fixturesRoot(f) / "escaped"};
  c.mustRefuse = true;
  return c;
}

/// A resumed search whose checkpoint or round files are not its own.
Case foreignSearchCase(const Fixtures& f, Random& random, const fs::path& folder) {
  const fs::path search = folder / "search";
  fs::create_directories(folder);
  fs::copy(f.search, search, fs::copy_options::recursive);
  const int kind = static_cast<int>(random.index(3));
  std::string what;
  if (kind == 0) {
    const fs::path round = search / ".rounds" / "round-00000.dataset.h5";
    fs::copy_file(f.otherSearch / ".rounds" / "round-00000.dataset.h5", round, fs::copy_options::overwrite_existing);
    what = "round 0's dataset from a search with another seed";
  } else if (kind == 1) {
    const fs::path checkpoint = search / "checkpoint.json";
    writeText(checkpoint, replaceFirst(textOf(checkpoint), "\"sample\":([0-9])", "\"sample\":1$1"));
    what = "checkpoint.json edited (a sample index)";
  } else {
    const fs::path round = search / ".rounds" / "round-00001.traces.h5";
    const std::string bytes = textOf(round);
    writeText(round, bytes.substr(0, bytes.size() / 2));
    what = "round 1's traces cut short";
  }
  Case c;
  c.name = "hostile/foreign-search: " + what;
  c.args = {"search", (sourceDir() / "scenarios" / "acc.yaml").string(), "-c", "d_min < 8", "--surrogate", "random",
            "--budget", "40", "--initial", "10", "--round", "10", "--pool", "100", "--out", search.string()};
  c.outputs = {search};
  c.mustRefuse = true;
  c.timeout = std::chrono::seconds(30);  // refused at the start, not after the budget
  return c;
}

/// A sharded sweep whose shard manifest was edited, or whose shard holds another run's files.
Case foreignShardCase(const Fixtures& f, Random& random, const fs::path& folder) {
  const fs::path sweep = folder / "sweep";
  fs::create_directories(folder);
  fs::copy(f.sweep, sweep, fs::copy_options::recursive);
  const fs::path shard = sweep / "shards" / "shard-0000-of-0002";
  const int kind = static_cast<int>(random.index(3));
  std::string what;
  if (kind == 0) {
    auto manifest = nlohmann::json::parse(textOf(shard / "manifest.json"));
    manifest["seed"] = 99;
    manifest["shard"]["seed"] = 99;
    writeText(shard / "manifest.json", manifest.dump(2));
    what = "shard 0's manifest seed edited";
  } else if (kind == 1) {
    // Another run's files with a manifest made to match them (sizes and hashes): the records disagree.
    for (const char* file : {"dataset.h5", "traces.h5"}) {
      fs::copy_file(f.run / file, shard / file, fs::copy_options::overwrite_existing);
    }
    auto manifest = nlohmann::json::parse(textOf(shard / "manifest.json"));
    const auto run_manifest = nlohmann::json::parse(textOf(f.run / "manifest.json"));
    for (const char* file : {"dataset.h5", "traces.h5"}) manifest["outputs"][file] = run_manifest["outputs"][file];
    manifest.erase("manifest_sha256");
    writeText(shard / "manifest.json", manifest.dump(2));
    what = "shard 0 holds another run's dataset and traces";
  } else {
    Case c;
    c.name = "hostile/foreign-shard: dataset validate of a shard whose manifest seed was edited";
    auto manifest = nlohmann::json::parse(textOf(shard / "manifest.json"));
    manifest["seed"] = 7;
    manifest.erase("manifest_sha256");
    writeText(shard / "manifest.json", manifest.dump(2));
    c.args = {"dataset", "validate", shard.string()};
    c.exitOneIsAVerdict = true;
    c.outputs = {sweep};
    c.mustRefuse = true;
    return c;
  }
  Case c;
  c.name = "hostile/foreign-shard: " + what + ", then merge";
  c.args = {"merge", sweep.string()};
  c.outputs = {sweep};
  c.mustRefuse = true;
  return c;
}

}  // namespace

std::vector<Case> issueReproductionCases(const Fixtures& fixtures, Random& random, std::size_t /*count*/) {
  // Issue 29's reproductions that are numbers or XML of an .xosc, each exactly as reported
  // (the other classes' generators draw from the issue's own examples already).
  const std::vector<std::pair<std::string, std::string>> numbers = {
      {"vsd-sumo.seed", "abc"},  {"vsd-sumo.seed", ""},    {"vsd-sumo.seed", "nan"},
      {"vsd-sumo.seed", "18446744073709551616"},           {"vsd-sumo.sample", "-1"},
      {"vsd-sumo.sample", "1.5"}, {"vehicle length", "1e300"}, {"Performance maxSpeed", "nan"},
      {"Performance maxDeceleration", "-5"},               {"collision action", "explode"},
      {"vsd-sumo.road.x_range", "900"},                    {"vsd-sumo.road.extension", "1e9"},
      {"vsd-sumo.step", "1e-5"}, {"StopTrigger time", "1e6"}, {"StopTrigger time", "1e9"}};
  std::vector<Case> cases;
  for (const auto& [target, value] : numbers) {
    cases.push_back(xoscNumberCaseWith(fixtures, random, caseFolder(fixtures, "issue29", cases.size()), target, value));
    cases.back().mustRefuse = true;  // every one of them is out of range or malformed
  }
  // Billion laughs: refused for its entity declarations, with nothing expanded (the listed
  // peak memory).
  cases.push_back(hostileXmlCaseOfKind(fixtures, random, caseFolder(fixtures, "issue29", cases.size()), 0));
  for (auto& c : cases) c.name = "issue29/" + c.name.substr(c.name.find('/') + 1);
  return cases;
}

std::vector<Case> hostileInputCases(const Fixtures& fixtures, Random& random, std::size_t count) {
  using Generator = Case (*)(const Fixtures&, Random&, const fs::path&);
  // Every class once per round of cases, in this order: the CI count covers each.
  const std::vector<Generator> generators = {xoscNumberCase,       hostileXmlCase,  specialFileCase,
                                             geometryCase,         optionInjectionCase, traversalCase,
                                             foreignSearchCase,    foreignShardCase};
  std::vector<Case> cases;
  for (std::size_t i = 0; i < count; ++i) {
    cases.push_back(generators[i % generators.size()](fixtures, random, caseFolder(fixtures, "hostile", i)));
  }
  return cases;
}

}  // namespace vsd::fuzz
