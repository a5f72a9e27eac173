#include "osc_expression.hpp"

#include <fmt/format.h>
#include <muParser.h>

#include <cctype>
#include <cmath>
#include <deque>

#include "vsd/core/error.hpp"
#include "vsd/core/numbers.hpp"
#include "xml_support.hpp"

namespace vsd::interop::osc {

namespace {

double roundHalfAway(double x) { return std::round(x); }
double floorOf(double x) { return std::floor(x); }
double ceilOf(double x) { return std::ceil(x); }
double power(double x, double y) { return std::pow(x, y); }
double notOf(double x) { return x == 0.0 ? 1.0 : 0.0; }
double remainderOf(double x, double y) { return std::fmod(x, y); }

bool isNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool isNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

/// A number from a parameter's text; booleans are 1/0 (the standard's expressions allow them).
std::optional<double> numericValue(const std::string& text) {
  if (text == "true") return 1.0;
  if (text == "false") return 0.0;
  try {
    return parseReal(text, NumberRange::any(), "", "");
  } catch (const ConfigError&) {
    return std::nullopt;
  }
}

}  // namespace

double evaluateExpression(const std::string& text, const ParameterValues& parameters, const std::string& where) {
  const auto fail = [&](const std::string& why) -> ConfigError {
    return ConfigError(fmt::format("{}: expression ${{{}}}: {}", where, text, why));
  };
  mu::Parser parser;
  std::deque<double> values;  // muparser binds variables by address: a deque never moves its elements
  std::string translated;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '$' || isNameStart(c)) {
      const std::size_t start = c == '$' ? i + 1 : i;
      std::size_t end = start;
      while (end < text.size() && isNameChar(text[end])) ++end;
      const std::string name = text.substr(start, end - start);
      i = end;
      if (c != '$') {
        // Words of the standard's grammar; other names are muparser's functions (sqrt, sin, ...).
        translated += name == "and" ? "&&" : name == "or" ? "||" : name == "true" ? "1" : name == "false" ? "0" : name;
        continue;
      }
      const auto found = parameters.find(name);
      if (name.empty() || found == parameters.end()) throw fail(fmt::format("${} is not a declared parameter", name));
      const auto number = numericValue(found->second);
      if (!number) throw fail(fmt::format("${} is '{}', not a number", name, found->second));
      values.push_back(*number);
      const std::string variable = fmt::format("osc_p{}", values.size());
      parser.DefineVar(variable, &values.back());
      translated += variable;
      continue;
    }
    translated += c;
    ++i;
  }
  try {
    parser.DefineFun("round", roundHalfAway);
    parser.DefineFun("floor", floorOf);
    parser.DefineFun("ceil", ceilOf);
    parser.DefineFun("pow", power);
    parser.DefineFun("not", notOf);
    parser.DefineOprt("%", remainderOf, mu::prMUL_DIV);
    parser.SetExpr(translated);
    const double result = parser.Eval();
    if (!std::isfinite(result)) throw fail(fmt::format("evaluates to {}, expected a finite number", result));
    return result;
  } catch (const mu::Parser::exception_type& error) {
    throw fail(error.GetMsg());
  }
}

std::string resolveValue(const std::string& value, const ParameterValues& parameters, const std::string& where) {
  if (value.size() >= 3 && value.rfind("${", 0) == 0 && value.back() == '}') {
    return xml::number(evaluateExpression(value.substr(2, value.size() - 3), parameters, where));
  }
  if (!value.empty() && value[0] == '$') {
    const auto found = parameters.find(value.substr(1));
    if (found == parameters.end()) {
      throw ConfigError(fmt::format("{}: {} refers to an undeclared parameter", where, value));
    }
    return found->second;
  }
  return value;
}

}  // namespace vsd::interop::osc
