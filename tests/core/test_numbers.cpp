// Issue 29: one reading of numbers for every format, bounded reads of whole files, paths
// a file names kept inside its folder, and the allow-list of SUMO/netconvert options.
#include <gmock/gmock.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/tool_options.hpp"

using namespace vsd;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

/// The ConfigError message of `action`, or "" if it did not throw one.
template <typename Action>
std::string refusal(Action action) {
  try {
    action();
  } catch (const ConfigError& error) {
    return error.what();
  }
  return {};
}

/// What asFixedDecimalText stands for: the number's fixed-point text, read back.
double readBackFromText(double value, int decimals) {
  char text[400];
  const auto end = std::to_chars(text, text + sizeof(text), value, std::chars_format::fixed, decimals).ptr;
  double parsed = 0.0;
  std::from_chars(text, end, parsed);
  return parsed;
}

bool sameBits(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

/// Coordinates of a network file (m, signed, up to 200 km).
std::vector<double> randomCoordinates() {
  std::mt19937_64 random(20261127);
  std::uniform_real_distribution<double> coordinate(-2e5, 2e5);
  std::vector<double> coordinates;
  for (int i = 0; i < 200'000; ++i) coordinates.push_back(coordinate(random));
  return coordinates;
}

/// Coordinates and numbers around them: signed, near zero, near and at the ties of two
/// decimals, around 2^52, huge, and not finite.
std::vector<double> numbersToWrite() {
  std::mt19937_64 random(20261128);
  std::uniform_real_distribution<double> small(-0.02, 0.02);
  std::uniform_int_distribution<std::int64_t> hundredths(-20'000'000, 20'000'000);
  // Around 2^52 (where n + 0.5 stops being a double) and beyond 2^53 (no fractions at all).
  std::vector<double> numbers = {0.0, -0.0, 0.125, -0.125, 0.375, 2.5, -2.5, 1.005, 2.675, 1e12, -1e20, 4.35e15,
                                 123456789012.345678, 4503599627370495.5, -4503599627370495.5, 4503599627370497.0,
                                 9007199254740993.0, 1.2345678901234567e17,
                                 std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                 -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::denorm_min(),
                                 -std::numeric_limits<double>::denorm_min()};
  const auto coordinates = randomCoordinates();
  numbers.insert(numbers.end(), coordinates.begin(), coordinates.end());
  for (int i = 0; i < 20'000; ++i) numbers.push_back(small(random));
  for (int i = 0; i < 50'000; ++i) {
    const double tie = (static_cast<double>(hundredths(random)) + 0.5) / 100.0;  // x.xx5, as near as a double gets
    numbers.push_back(tie);
    numbers.push_back(std::nextafter(tie, 0.0));
    numbers.push_back(std::nextafter(tie, 1e300));
  }
  return numbers;
}

}  // namespace

// Network files are written and read back with two (SUMO) or six (plain XML) decimals for
// every coordinate; the digits are found by arithmetic where that is certain, and the result
// must be the text's, bit for bit, or the lanes vsd-sumo measures on would differ from SUMO's.
TEST(FixedDecimal, ReadsBackAndWritesEveryNumberExactlyAsItsTextDoes) {
  const auto numbers = numbersToWrite();
  FixedDecimalBuffer buffer;
  for (const int decimals : {0, 2, 6, 15}) {
    for (const double value : numbers) {
      ASSERT_TRUE(sameBits(asFixedDecimalText(value, decimals), readBackFromText(value, decimals)))
          << fmt::format("{:.17g} with {} decimals: {:.17g}, the text reads back as {:.17g}", value, decimals,
                         asFixedDecimalText(value, decimals), readBackFromText(value, decimals));
      ASSERT_EQ(fixedDecimalText(value, decimals, buffer), fmt::format("{:.{}f}", value, decimals))
          << fmt::format("{:.17g} with {} decimals", value, decimals);
    }
  }
  // For network coordinates (2 or 6 decimals) the cheap path is the usual one.
  const auto coordinates = randomCoordinates();
  for (const int decimals : {2, 6}) {
    const auto decided = std::count_if(coordinates.begin(), coordinates.end(),
                                       [&](double value) { return fixedDecimalDigits(value, decimals).has_value(); });
    EXPECT_GT(static_cast<double>(decided), 0.99 * static_cast<double>(coordinates.size())) << decimals;
  }
  EXPECT_THROW(fixedDecimalText(1.0, 16, buffer), Error);  // beyond the digits a double's value can need
  EXPECT_EQ(fixedDecimalDigits(1.236, 2), 124);
  EXPECT_EQ(fixedDecimalDigits(-1.234, 2), -123);
  EXPECT_EQ(fixedDecimalDigits(-0.004, 2), 0);
  EXPECT_EQ(fixedDecimalText(-0.004, 2, buffer), "-0.00");
  EXPECT_FALSE(fixedDecimalDigits(0.125, 2).has_value());  // a tie: only the text decides
  EXPECT_FALSE(fixedDecimalDigits(1e16, 0).has_value());   // beyond 2^52
}

TEST(Numbers, DecimalTextIsReadWholeAndFiniteNumbersAreRefusedByName) {
  EXPECT_EQ(parseReal("12.5", NumberRange::any(), "f", "x"), 12.5);
  EXPECT_EQ(parseReal("+3", NumberRange::any(), "f", "x"), 3.0);
  EXPECT_EQ(parseReal("-1e-3", NumberRange::any(), "f", "x"), -1e-3);
  EXPECT_EQ(parseReal(".5", NumberRange::any(), "f", "x"), 0.5);
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"nan", "NaN is not a number"},       {".nan", "NaN is not a number"}, {"-inf", "infinite"},
      {".inf", "infinite"},                 {"Infinity", "infinite"},        {"1e400", "beyond the range of a double"},
      {"", "empty"},                        {"abc", "not a decimal number"}, {"0x10", "not a decimal number"},
      {"1,5", "not a decimal number"},      {"3 m", "not a decimal number"}, {" 3", "not a decimal number"},
  };
  for (const auto& [text, why] : refused) {
    const std::string message = refusal([&] { parseReal(text, NumberRange::any(), "file.xosc:3: <Dimensions>", "length"); });
    EXPECT_EQ(message, "file.xosc:3: <Dimensions>: length: got '" + text + "', expected a finite number (" + why + ")")
        << text;
  }
}

TEST(Numbers, RangesAreStatedInTheMessage) {
  const NumberRange length = NumberRange::aboveUpTo(0.0, 100.0);
  EXPECT_EQ(parseReal("100", length, "f", "length"), 100.0);
  EXPECT_EQ(refusal([&] { parseReal("0", length, "f", "length"); }),
            "f: length: got '0', expected a finite number in (0, 100]");
  EXPECT_EQ(refusal([&] { parseReal("1e300", length, "f", "length"); }),
            "f: length: got '1e300', expected a finite number in (0, 100]");
  EXPECT_EQ(refusal([&] { checkReal(std::nan(""), NumberRange::atLeast(0.0), "f", "maxSpeed"); }),
            "f: maxSpeed: got 'nan', expected a finite number >= 0 (NaN is not a number)");
  EXPECT_EQ(refusal([&] { checkReal(-1.0, NumberRange::atLeast(0.0), "f", "maxSpeed"); }),
            "f: maxSpeed: got '-1', expected a finite number >= 0");
}

TEST(Numbers, WholeNumbersNeitherWrapNorComeFromFractions) {
  constexpr auto kMax = std::numeric_limits<std::uint64_t>::max();
  EXPECT_EQ(parseUnsigned("18446744073709551615", kMax, "f", "seed"), kMax);
  EXPECT_EQ(parseUnsigned("007", kMax, "f", "seed"), 7u);  // decimal, not octal
  EXPECT_EQ(parseUnsigned("1e3", kMax, "f", "seed"), 1000u);
  EXPECT_EQ(refusal([&] { parseUnsigned("-1", kMax, "f", "vsd-sumo.seed"); }),
            "f: vsd-sumo.seed: got '-1', expected a whole number 0 .. 18446744073709551615");
  EXPECT_EQ(refusal([&] { parseUnsigned("1.5", kMax, "f", "seed"); }),
            "f: seed: got '1.5', expected a whole number 0 .. 18446744073709551615 (a fraction)");
  EXPECT_EQ(refusal([&] { parseUnsigned("18446744073709551616", kMax, "f", "seed"); }),
            "f: seed: got '18446744073709551616', expected a whole number 0 .. 18446744073709551615 (out of range)");
  EXPECT_THAT(refusal([&] { parseUnsigned("abc", kMax, "f", "seed"); }), HasSubstr("(not a decimal number)"));
  EXPECT_THAT(refusal([&] { parseUnsigned("nan", kMax, "f", "seed"); }), HasSubstr("(NaN is not a number)"));
  EXPECT_THAT(refusal([&] { parseUnsigned("", kMax, "f", "seed"); }), HasSubstr("(empty)"));
  EXPECT_EQ(parseInteger("-16", -16, 16, "f", "laneId"), -16);
  EXPECT_EQ(refusal([&] { parseInteger("-17", -16, 16, "f", "laneId"); }),
            "f: laneId: got '-17', expected a whole number -16 .. 16");
  EXPECT_EQ(parseInteger("-9223372036854775808", std::numeric_limits<std::int64_t>::min(), 0, "f", "x"),
            std::numeric_limits<std::int64_t>::min());
}

TEST(Numbers, StepAndDurationBoundsHoldBeforeAnyArrayIsSized) {
  EXPECT_EQ(checkStep(0.2, "f", "step"), 0.2);
  EXPECT_THAT(refusal([] { checkStep(1e-5, "f", "vsd-sumo.step"); }),
              HasSubstr("vsd-sumo.step: got '1e-05', expected a multiple of 0.001 s in 0.001 .. 10 s"));
  EXPECT_EQ(checkDurationSteps(5.0, 0.2, "f", "duration"), 25);
  EXPECT_THAT(refusal([] { checkDurationSteps(1e6, 0.2, "f", "duration"); }),
              HasSubstr("duration: got '1000000', expected a whole multiple of the step (0.2 s), 1 .. 1000 steps"));
  EXPECT_THAT(refusal([] { checkDurationSteps(1e9, 0.2, "f", "duration"); }), HasSubstr("got '1000000000'"));
}

TEST(ReadLimits, SpecialFilesAreRefusedWithoutBlockingAndLargeFilesBeforeTheyAreRead) {
  TemporaryDirectory dir;
  for (const char* device : {"/dev/zero", "/dev/urandom"}) {
    try {
      readTextFile(device, read_limits::kScenario);
      FAIL() << device << " was read";
    } catch (const IoError& error) {
      EXPECT_THAT(error.what(), HasSubstr("a character device, expected a regular file"));
    }
  }
  const fs::path fifo = dir.path() / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(readTextFile(fifo), IoError);  // no writer: it must not wait for one
  EXPECT_THROW(sha256OfFile(fifo), IoError);
  EXPECT_THROW(readTextFile(dir.path()), IoError);

  const fs::path big = dir.path() / "big.xml";
  std::ofstream(big) << std::string(2048, 'x');
  const ReadLimit small{"test file", 1024, "VSD_TEST_LIMIT_BYTES"};
  ::unsetenv("VSD_TEST_LIMIT_BYTES");
  try {
    readTextFile(big, small);
    FAIL() << "a file over its limit was read";
  } catch (const IoError& error) {
    EXPECT_THAT(error.what(), HasSubstr("2048 bytes: larger than the 1024 bytes a test file may have (set "
                                        "VSD_TEST_LIMIT_BYTES to a larger byte count"));
  }
  ::setenv("VSD_TEST_LIMIT_BYTES", "4096", 1);
  EXPECT_EQ(readTextFile(big, small).size(), 2048u);
  ::setenv("VSD_TEST_LIMIT_BYTES", "lots", 1);  // not a byte count: the default holds
  EXPECT_THROW(readTextFile(big, small), IoError);
  ::unsetenv("VSD_TEST_LIMIT_BYTES");
}

TEST(PathsInFiles, StayInsideTheFilesFolderAfterResolvingLinks) {
  TemporaryDirectory dir;
  const fs::path base = dir.path() / "scenario";
  fs::create_directories(base / "roads");
  std::ofstream(base / "roads" / "r.xodr") << "x";
  std::ofstream(dir.path() / "outside.xodr") << "x";
  EXPECT_EQ(requirePathInside(base, "roads/r.xodr", "f", "filepath"), fs::canonical(base / "roads" / "r.xodr"));
  EXPECT_EQ(requirePathInside(base, base / "roads" / "r.xodr", "f", "filepath"), fs::canonical(base / "roads" / "r.xodr"));
  for (const fs::path& escaping : {fs::path("../outside.xodr"), fs::path("roads/../../outside.xodr"),
                                   fs::path("/dev/zero"), fs::path("/etc/passwd")}) {
    EXPECT_THAT(refusal([&] { requirePathInside(base, escaping, "a.xosc:4: <LogicFile>", "filepath"); }),
                HasSubstr("a.xosc:4: <LogicFile>: filepath: got '" + escaping.string() + "', expected a path inside"))
        << escaping;
  }
  fs::create_symlink(dir.path() / "outside.xodr", base / "link.xodr");  // a link out of the folder
  EXPECT_THAT(refusal([&] { requirePathInside(base, "link.xodr", "f", "filepath"); }), HasSubstr("resolves to"));

  requireSafeName("paper-quick_2.v1", "f", "name");
  for (const std::string bad : {"", "../../X", "a/b", ".hidden", "..", "a b", "x\\y"}) {
    EXPECT_THAT(refusal([&] { requireSafeName(bad, "spec.yaml:2: name", "name"); }), HasSubstr("a plain name")) << bad;
  }
}

TEST(ToolOptions, OnlyOptionsThatNameNoFileReachSumoOrNetconvert) {
  checkScenarioToolOptions(SumoTool::Sumo, {"--precision", "6", "--device.ssm.probability", "1",
                                            "--device.ssm.measures", "TTC DRAC", "--eager-insert",
                                            "--step-method.ballistic", "true", "--seed=3"},
                           "f", "sumo_options");
  checkScenarioToolOptions(SumoTool::Netconvert, {"--no-turnarounds", "--junctions.corner-detail", "5"}, "f",
                           "netconvert_options");
  const std::vector<std::pair<std::vector<std::string>, std::string>> refused = {
      {{"--fcd-output", "/tmp/x.xml"}, "sumo_options[0]: got '--fcd-output'"},
      {{"--fcd-output=/tmp/x.xml"}, "sumo_options[0]: got '--fcd-output=/tmp/x.xml'"},
      {{"-c", "other.sumocfg"}, "sumo_options[0]: got '-c'"},
      {{"--device.ssm.file", "x"}, "got '--device.ssm.file'"},
      {{"--precision", "/etc/passwd"}, "sumo_options[1] (value of --precision): got '/etc/passwd'"},
      {{"--precision"}, "expected a value after --precision"},
      {{"--eager-insert", "/tmp/x"}, "sumo_options[1]: got '/tmp/x', expected true or false"},
      {{"--device.ssm.measures", "../x"}, "plain words or numbers"},
      {{"--precision", "nan"}, "(NaN is not a number)"},
      {{"stray"}, "got 'stray'"},
  };
  for (const auto& [options, expected] : refused) {
    EXPECT_THAT(refusal([&] { checkScenarioToolOptions(SumoTool::Sumo, options, "f", "sumo_options"); }),
                HasSubstr(expected))
        << options.front();
  }
  EXPECT_THAT(refusal([] {
                checkScenarioToolOptions(SumoTool::Netconvert, {"--plain-output-prefix", "/tmp/p"}, "f",
                                         "netconvert_options");
              }),
              HasSubstr("an option a scenario file may pass to netconvert (one that names no file"));
  EXPECT_TRUE(isCollisionAction("teleport"));
  EXPECT_FALSE(isCollisionAction("explode"));
}

TEST(Manifests, AnEditedManifestIsRefusedAndAnOlderOneWithoutChecksumIsRead) {
  TemporaryDirectory dir;
  nlohmann::json manifest = {{"seed", 1}, {"outputs", nlohmann::json::object()}};
  writeTextFileAtomically(dir.path() / "manifest.json", sealManifest(manifest).dump(2));
  EXPECT_EQ(readManifest(dir.path()).at("seed"), 1);
  auto edited = sealManifest(manifest);
  edited["seed"] = 2;
  writeTextFileAtomically(dir.path() / "manifest.json", edited.dump(2));
  try {
    readManifest(dir.path());
    FAIL() << "an edited manifest was read";
  } catch (const DatasetError& error) {
    EXPECT_THAT(error.what(), HasSubstr("edited after it was written"));
  }
  EXPECT_FALSE(checkOutputFolder(dir.path(), true).empty());
  writeTextFileAtomically(dir.path() / "manifest.json", manifest.dump(2));  // written before checksums existed
  EXPECT_EQ(readManifest(dir.path()).at("seed"), 1);
}
