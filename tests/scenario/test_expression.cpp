#include <gtest/gtest.h>

#include "vsd/core/error.hpp"
#include "vsd/scenario/expression.hpp"

using namespace vsd;
using vsd::scenario::Expression;

TEST(Expression, EvaluatesOverNamedVariables) {
  const auto expression = Expression::compile("-50 + 2*v_ego", {"a0", "v_ego"}, "test");
  EXPECT_FALSE(expression.isConstant());
  EXPECT_DOUBLE_EQ(expression.evaluate({99.0, 10.0}), -30.0);
  const auto poly = Expression::compile("a0 + a1*x + a3*x^3", {"a0", "a1", "a3", "x"}, "test");
  EXPECT_DOUBLE_EQ(poly.evaluate({1.0, 0.5, 0.001, 10.0}), 1.0 + 5.0 + 1.0);
}

TEST(Expression, NumbersAreConstants) {
  const auto expression = Expression::compile("3.5", {}, "test");
  EXPECT_TRUE(expression.isConstant());
  EXPECT_DOUBLE_EQ(expression.evaluate({}), 3.5);
  EXPECT_EQ(expression.text(), "3.5");
}

TEST(Expression, UnknownNameIsNamedWithTheKnownOnes) {
  try {
    Expression::compile("-50 + 2*v_eg", {"a0", "v_ego"}, "acc.yaml:14: inputs[5].max");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("acc.yaml:14: inputs[5].max"), std::string::npos) << message;
    EXPECT_NE(message.find("'v_eg'"), std::string::npos) << message;
    EXPECT_NE(message.find("a0, v_ego"), std::string::npos) << message;
  }
}

TEST(Expression, SyntaxErrorsAreConfigErrors) {
  EXPECT_THROW(Expression::compile("2 * (v + 1", {"v"}, "test"), ConfigError);
  EXPECT_THROW(Expression::compile("2 +* v", {"v"}, "test"), ConfigError);
}
