#include "osc_parameters.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "vsd/core/error.hpp"
#include "vsd/core/numbers.hpp"

namespace vsd::interop::osc {

namespace {

enum class Kind { Real, Whole, Boolean, Text };

/// A declared parameterType: its kind and, for whole numbers, the values the type holds.
struct Type {
  Kind kind = Kind::Text;
  double lowest = 0.0;
  double highest = 0.0;
  const char* name = "";
};

Type typeOf(const xml::Reader& reader, const pugi::xml_node& declaration) {
  const std::string type = reader.oneOf(declaration, "parameterType",
                                        {"double", "int", "integer", "unsignedInt", "unsignedShort", "string",
                                         "boolean", "dateTime"});
  if (type == "double") return {Kind::Real};
  if (type == "boolean") return {Kind::Boolean};
  if (type == "string" || type == "dateTime") return {Kind::Text};
  if (type == "unsignedInt") return {Kind::Whole, 0.0, 4294967295.0, "an unsignedInt"};
  if (type == "unsignedShort") return {Kind::Whole, 0.0, 65535.0, "an unsignedShort"};
  return {Kind::Whole, -2147483648.0, 2147483647.0, "an int"};
}

/// Checks `value` against the declared type; returns it as a number for numeric types.
std::optional<double> typed(const Type& type, const std::string& value, const std::string& where,
                            const std::string& name) {
  switch (type.kind) {
    case Kind::Text:
      return std::nullopt;
    case Kind::Boolean:
      if (value != "true" && value != "false") throw ConfigError::field(where, name, value, "true or false (boolean)");
      return value == "true" ? 1.0 : 0.0;
    case Kind::Real:
      return parseReal(value, NumberRange::any(), where, name);
    case Kind::Whole: {
      const double number = parseReal(value, NumberRange::any(), where, name);
      if (number != std::floor(number) || number < type.lowest || number > type.highest) {
        throw ConfigError::field(where, name, value,
                                 fmt::format("{} ({} .. {})", type.name, xml::number(type.lowest),
                                             xml::number(type.highest)));
      }
      return number;
    }
  }
  return std::nullopt;
}

bool holds(const std::string& rule, double value, double limit) {
  if (rule == "equalTo") return value == limit;
  if (rule == "notEqualTo") return value != limit;
  if (rule == "greaterThan") return value > limit;
  if (rule == "lessThan") return value < limit;
  if (rule == "greaterOrEqual") return value >= limit;
  return value <= limit;  // lessOrEqual
}

}  // namespace

Parameters readParameters(xml::Reader& reader, const pugi::xml_node& parent, const ParameterValues& outer,
                          const ParameterValues& assigned, const std::string& assigned_where) {
  Parameters result;
  result.values = outer;
  reader.setParameters(result.values);
  const pugi::xml_node declarations = parent.child("ParameterDeclarations");
  std::map<std::string, int> declared_at;  // name -> line of its (latest) declaration
  if (declarations) {
    reader.requireSubset(declarations, {"ParameterDeclaration"});
    for (const pugi::xml_node& declaration : declarations.children("ParameterDeclaration")) {
      reader.requireSubset(declaration, {"ConstraintGroup"});
      const std::string name = declaration.attribute("name").value();
      if (name.empty()) reader.fail(declaration, "attribute 'name' is missing");
      // Declared again in one scope: the later value replaces the earlier one, as esmini reads it
      // (with a warning; esmini's own follow_reference and vehicle catalog do so). Said, and one input.
      if (const auto earlier = declared_at.find(name); earlier != declared_at.end()) {
        result.notes.emplace_back(reader.where(declaration),
                                  fmt::format("parameter '{}' declared again: this declaration replaces the one at "
                                              "line {}, as esmini reads it",
                                              name, earlier->second));
        const auto same = [&](const auto& entry) { return entry.first == name; };
        result.numeric.erase(std::remove_if(result.numeric.begin(), result.numeric.end(), same), result.numeric.end());
        result.strings.erase(std::remove_if(result.strings.begin(), result.strings.end(), same), result.strings.end());
      }
      declared_at[name] = reader.line(declaration);
      const Type type = typeOf(reader, declaration);
      const auto given = assigned.find(name);
      // A declared value may refer to the parameters before it (the reader resolves it); an
      // assigned one replaces it.
      if (given != assigned.end()) reader.leave(declaration, {"value"});
      const std::string value = given != assigned.end() ? given->second : reader.text(declaration, "value");
      const std::string where = given != assigned.end() ? assigned_where : reader.where(declaration);
      const auto number = typed(type, value, where, name);
      result.values[name] = value;
      reader.setParameters(result.values);
      if (number && type.kind != Kind::Boolean) {
        result.numeric.emplace_back(name, *number);
      } else if (!number) {
        result.strings.emplace_back(name, value);
      }
    }
  }
  for (const auto& [name, value] : assigned) {
    if (declared_at.count(name) == 0) {
      throw ConfigError(fmt::format("{}: assigns parameter '{}', which {} does not declare", assigned_where, name,
                                    reader.file().string()));
    }
  }
  return result;
}

std::optional<std::string> violatedConstraint(const xml::Reader& reader, const pugi::xml_node& parent,
                                              const ParameterValues& values) {
  const pugi::xml_node declarations = parent.child("ParameterDeclarations");
  for (const pugi::xml_node& declaration : declarations.children("ParameterDeclaration")) {
    if (!declaration.child("ConstraintGroup")) continue;
    const std::string name = declaration.attribute("name").value();
    const Type type = typeOf(reader, declaration);
    const std::string value = values.at(name);
    std::vector<std::string> groups;
    bool satisfied = false;
    for (const pugi::xml_node& group : declaration.children("ConstraintGroup")) {
      reader.requireSubset(group, {"ValueConstraint"});
      bool all = true;
      std::vector<std::string> terms;
      for (const pugi::xml_node& constraint : group.children("ValueConstraint")) {
        const std::string rule = reader.oneOf(constraint, "rule", {"equalTo", "notEqualTo", "greaterThan", "lessThan",
                                                                   "greaterOrEqual", "lessOrEqual"});
        // Resolved against the whole set, not the reader's parameters so far: read here.
        reader.leave(constraint, {"value"});
        const std::string limit = resolveValue(constraint.attribute("value").value(), values, reader.where(constraint));
        terms.push_back(fmt::format("{} {}", rule, limit));
        if (type.kind == Kind::Text) {
          if (rule != "equalTo" && rule != "notEqualTo") {
            reader.fail(constraint, fmt::format("rule {} on the string parameter '{}': expected equalTo or notEqualTo",
                                                rule, name));
          }
          all = all && ((value == limit) == (rule == "equalTo"));
        } else {
          const double limit_number = parseReal(limit, NumberRange::any(), reader.where(constraint), "value");
          all = all && holds(rule, *typed(type, value, reader.where(declaration), name), limit_number);
        }
      }
      if (terms.empty()) reader.fail(group, "expected at least one <ValueConstraint>");
      groups.push_back(fmt::format("{}", fmt::join(terms, " and ")));
      satisfied = satisfied || all;
    }
    if (!satisfied) {
      return fmt::format("{}: parameter '{}' = '{}' violates its constraints ({}); OpenSCENARIO: not executed",
                         reader.where(declaration), name, value, fmt::join(groups, ") or ("));
    }
  }
  return std::nullopt;
}

}  // namespace vsd::interop::osc
