#pragma once
// OpenSCENARIO parameters and expressions (private to the interop module).
//
// `$name` stands for a parameter's value; `${...}` (OpenSCENARIO >= 1.1) is an
// expression over numeric parameters. The expression is evaluated by muparser after
// OpenSCENARIO's own syntax is translated (a `$` before a name dropped, `and`/`or` to
// `&&`/`||`, `true`/`false` to 1/0); the standard's functions muparser lacks (round,
// floor, ceil, pow, not, and `%`) are defined for it. Nothing parses arithmetic by hand.

#include <map>
#include <string>

namespace vsd::interop::osc {

/// Parameter values by name, as text (the standard's values are strings typed by the declaration).
using ParameterValues = std::map<std::string, std::string>;

/// Value of the expression body `text` (the part between "${" and "}"). Every `$name`
/// must be a parameter whose value is a number (booleans count as 1/0). Throws ConfigError
/// "<where>: expression ${...}: <why>" for syntax errors, unknown or non-numeric
/// parameters and results that are not finite numbers.
double evaluateExpression(const std::string& text, const ParameterValues& parameters, const std::string& where);

/// An attribute value with parameters resolved: "$name" -> the parameter's value,
/// "${...}" -> the expression's value (shortest exact text), anything else as it is.
/// Throws ConfigError naming `where` for an undeclared parameter.
std::string resolveValue(const std::string& value, const ParameterValues& parameters, const std::string& where);

}  // namespace vsd::interop::osc
