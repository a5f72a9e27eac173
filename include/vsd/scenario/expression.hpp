#pragma once
// Numeric expressions in scenario files, e.g. `-50 + 2*v_ego` or
// `a0 + a1*x + a2*x^2 + a3*x^3` (muparser syntax: + - * / ^, parentheses,
// sin, cos, tan, sqrt, exp, log, abs, min, max, sum, avg, _pi, _e).
//
// An expression is compiled once against an ordered list of variable names and
// evaluated with values in that order. Not thread-safe: each worker process
// owns its scenarios.

#include <memory>
#include <string>
#include <vector>

namespace vsd::scenario {

class Expression {
 public:
  /// The constant 0.
  Expression() = default;
  static Expression constant(double value);

  /// Compiles `text` for the given variables. Throws ConfigError naming `where`
  /// (e.g. "acc.yaml:14: inputs[5].max") if the text does not parse or uses a
  /// name that is not in `variables` (the message lists the known names).
  static Expression compile(const std::string& text, const std::vector<std::string>& variables,
                            const std::string& where);

  /// Evaluates with `values[i]` bound to `variables[i]` of compile().
  double evaluate(const std::vector<double>& values) const;

  bool isConstant() const { return !impl_; }
  /// The source text ("3.5" for constants).
  const std::string& text() const { return text_; }

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;  // shared: muparser binds variables by address, so copies share one parser
  double constant_ = 0.0;
  std::string text_ = "0";
};

}  // namespace vsd::scenario
