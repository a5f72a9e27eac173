#include "vsd/scenario/expression.hpp"

#include <fmt/format.h>
#include <muParser.h>

#include <algorithm>
#include <cstdlib>

#include "vsd/core/error.hpp"

namespace vsd::scenario {

struct Expression::Impl {
  mu::Parser parser;
  std::vector<double> buffer;  // variable storage bound into the parser
  std::vector<std::size_t> used;  // indices of the variables the expression reads
};

Expression Expression::constant(double value) {
  Expression expression;
  expression.constant_ = value;
  expression.text_ = fmt::format("{}", value);
  return expression;
}

namespace {
bool parseNumber(const std::string& text, double& value) {
  const char* begin = text.c_str();
  char* end = nullptr;
  value = std::strtod(begin, &end);
  if (end == begin) return false;
  while (*end == ' ' || *end == '\t') ++end;
  return *end == '\0';
}
}  // namespace

Expression Expression::compile(const std::string& text, const std::vector<std::string>& variables,
                               const std::string& where) {
  double number = 0.0;
  if (parseNumber(text, number)) {
    Expression expression = constant(number);
    expression.text_ = text;
    return expression;
  }
  auto impl = std::make_shared<Impl>();
  impl->buffer.assign(variables.size(), 0.0);
  try {
    for (std::size_t i = 0; i < variables.size(); ++i) impl->parser.DefineVar(variables[i], &impl->buffer[i]);
    impl->parser.SetExpr(text);
    // GetUsedVar() parses without evaluating and also reports undefined names.
    const auto used = impl->parser.GetUsedVar();
    for (const auto& [name, address] : used) {
      const auto it = std::find(variables.begin(), variables.end(), name);
      if (it == variables.end()) {
        const std::string known = variables.empty() ? "none" : fmt::format("{}", fmt::join(variables, ", "));
        throw ConfigError(fmt::format("{}: expression '{}' uses unknown name '{}' (known here: {})", where, text,
                                      name, known));
      }
      impl->used.push_back(static_cast<std::size_t>(std::distance(variables.begin(), it)));
    }
    impl->parser.Eval();  // surfaces syntax errors now rather than at the first sample
  } catch (const mu::Parser::exception_type& error) {
    throw ConfigError(fmt::format("{}: cannot parse expression '{}': {} (at position {})", where, text,
                                  error.GetMsg(), error.GetPos()));
  }
  Expression expression;
  expression.impl_ = std::move(impl);
  expression.text_ = text;
  return expression;
}

double Expression::evaluate(const std::vector<double>& values) const {
  if (!impl_) return constant_;
  for (std::size_t index : impl_->used) impl_->buffer[index] = values[index];
  return impl_->parser.Eval();
}

}  // namespace vsd::scenario
