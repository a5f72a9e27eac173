// Criteria are comparisons (docs/cli.md "Criteria"): what is accepted, how it reads to
// muparser, and what is refused - by name, with the allowed forms.
#include <gtest/gtest.h>

#include "vsd/core/criterion_syntax.hpp"
#include "vsd/core/error.hpp"

using namespace vsd;

namespace {

std::string refusal(const std::string& text) {
  try {
    checkCriterion(text, "--criterion");
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "accepted";
}

}  // namespace

TEST(CriterionSyntax, ComparisonsCombinedWithAndOr) {
  EXPECT_EQ(checkCriterion("d_min < 2", "x").expression, "d_min < 2");
  const auto both = checkCriterion("ttc_min < 1 or d_min <= 0.5 and a_min > -6", "x");
  EXPECT_EQ(both.expression, "ttc_min < 1 || d_min <= 0.5 && a_min > -6");
  EXPECT_EQ(both.names, (std::vector<std::string>{"ttc_min", "d_min", "a_min"}));
  EXPECT_EQ(checkCriterion("(d_min + 1) < 2", "x").expression, "(d_min+1) < 2");
  EXPECT_EQ(checkCriterion("(d_min < 2 or a_min < -6) and abs(p_lat_max) >= 1e-3", "x").expression,
            "(d_min < 2 || a_min < -6) && abs(p_lat_max) >= 1e-3");
  EXPECT_EQ(checkCriterion("min(d_min, d_lon_min) < 2 * thw_min", "x").names,
            (std::vector<std::string>{"d_min", "d_lon_min", "thw_min"}));
  // The old spellings of and / or still work.
  EXPECT_EQ(checkCriterion("d_min < 2 || a_min < -6", "x").expression, "d_min < 2 || a_min < -6");
}

TEST(CriterionSyntax, AnythingElseIsRefusedByNameWithTheAllowedForms) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"d_min = 2", "'=' is not a comparison (it assigns)"},
      {"d_min", "'d_min' is not a comparison"},
      {"d_min < 2, a_min < 0", "unexpected ','"},
      {"d_min == 2", "'==' is not allowed"},
      {"1 < d_min < 2", "chained comparisons"},
      {"d_min < 1e400", "the number 1e400 is out of range"},
      {"d_min < 2 and", "it ends where a number or metric was expected"},
      {"d_min < 2 $", "unexpected character '$'"},
      {"", "it ends where a number or metric was expected"},
  };
  for (const auto& [text, expected] : cases) {
    const auto message = refusal(text);
    EXPECT_NE(message.find(expected), std::string::npos) << text << ": " << message;
    EXPECT_NE(message.find("expected comparisons (<, <=, >, >=) of metrics and numbers, combined with 'and' / 'or'"),
              std::string::npos)
        << message;
    EXPECT_EQ(message.rfind("--criterion: criterion '" + text + "': ", 0), 0u) << message;
  }
}

TEST(CriterionSyntax, NamedOnTheCommandLine) {
  EXPECT_EQ(splitNamedCriterion("close: d_min < 2", "--criterion").name, "close");
  EXPECT_EQ(splitNamedCriterion("close: d_min < 2", "--criterion").criterion, "d_min < 2");
  EXPECT_EQ(splitNamedCriterion(" d_min < 2 ", "--criterion").name, "d_min < 2");
  EXPECT_THROW(splitNamedCriterion("close:", "--criterion"), ConfigError);
}
