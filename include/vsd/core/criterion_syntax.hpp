#pragma once
// The one syntax of a pass/fail criterion, wherever one is written (`--criterion` of
// compare and search, a scenario's `criteria: [{name, fail_if}]`; docs/cli.md "Criteria"):
//
//   criterion  := comparison | criterion and criterion | criterion or criterion | ( criterion )
//   comparison := arithmetic OP arithmetic          OP: <  <=  >  >=
//   arithmetic := numbers, metric names, + - * / ^, parentheses, functions (abs, min, max, ...)
//
// e.g. `d_min < 2`, `ttc_min < 1 or d_min < 0.5`, `abs(a_min) > 6 and d_min < 2 * thw_min`.
// Checked before use: `d_min = 2` (muparser's assignment), a bare `d_min`, a list
// `d_min < 2, a_min < 0`, `==`, chained `1 < d_min < 2` and numbers beyond a double's
// range (`1e400`) are refused, each by name, with the allowed forms. `&&` and `||` are
// the old spellings of `and` / `or`: accepted with a one-line deprecation note.

#include <string>
#include <vector>

namespace vsd {

struct CheckedCriterion {
  std::string expression;          ///< the criterion in muparser syntax (and -> &&, or -> ||)
  std::vector<std::string> names;  ///< the variable names it reads, in order of first use
};

/// Parses and checks `text`; throws ConfigError "<where>: criterion '<text>': <problem>;
/// expected ..." (one line) if it is not a criterion.
CheckedCriterion checkCriterion(const std::string& text, const std::string& where);

/// A criterion as a flag gives it: "name: criterion" or a bare criterion (named after
/// itself); both parts trimmed. Throws ConfigError naming `where` for an empty part.
struct NamedCriterion {
  std::string name;
  std::string criterion;
};
NamedCriterion splitNamedCriterion(const std::string& text, const std::string& where);

}  // namespace vsd
