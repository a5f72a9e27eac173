#pragma once
// OpenSCENARIO ParameterDeclarations and ConstraintGroups (private to the interop module).
//
// Declarations are evaluated in file order: a value may be `$name` or `${...}` over the
// parameters declared before it (so a cycle cannot be written; a later or undeclared
// name is refused). Values assigned from outside (a ParameterValueDistribution's set, a
// CatalogReference's ParameterAssignments) replace the declared value and are typed by
// the declaration. Constraints (OpenSCENARIO 1.1+): the groups of a declaration are ORed,
// the constraints of a group ANDed; a violated one means "do not execute".

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "osc_expression.hpp"
#include "xml_support.hpp"

namespace vsd::interop::osc {

struct Parameters {
  ParameterValues values;  ///< every parameter in scope, resolved text
  /// Declared numeric parameters of this scope, in declaration order, with their values
  /// (the inputs of the imported scenario: a row of concrete.csv).
  std::vector<std::pair<std::string, double>> numeric;
  /// Declared string parameters of this scope, in order (catalog names, file paths, ...).
  std::vector<std::pair<std::string, std::string>> strings;
  /// Where and what to note (a parameter declared again), for the caller's findings.
  std::vector<std::pair<std::string, std::string>> notes;
};

/// Reads the <ParameterDeclarations> under `parent` (none: no parameters) on top of
/// `outer` (the enclosing scope), with `assigned` replacing declared values. Sets the
/// reader's parameters. Throws ConfigError "file:line: <ParameterDeclaration>: ..." for bad
/// types, unresolvable references, and assignments to undeclared parameters (`assigned_where`
/// names where those come from).
Parameters readParameters(xml::Reader& reader, const pugi::xml_node& parent, const ParameterValues& outer,
                          const ParameterValues& assigned, const std::string& assigned_where);

/// The first declaration under `parent` whose value violates its ConstraintGroups, as one
/// line "file:line: <ParameterDeclaration>: parameter X = v violates its constraints (...)";
/// nullopt if all hold. Constraint values may be expressions over the whole set.
std::optional<std::string> violatedConstraint(const xml::Reader& reader, const pugi::xml_node& parent,
                                              const ParameterValues& values);

}  // namespace vsd::interop::osc
