// Criteria are comparisons (vsd/core/criterion_syntax.hpp): a small recursive-descent
// parser that checks the text and writes it out in muparser syntax.

#include "vsd/core/criterion_syntax.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <set>

#include "vsd/core/error.hpp"

namespace vsd {

namespace {

constexpr const char* kAllowed =
    "expected comparisons (<, <=, >, >=) of metrics and numbers, combined with 'and' / 'or', e.g. 'd_min < 2' or "
    "'ttc_min < 1 or d_min < 0.5'";

enum class Kind { Number, Name, Operator, End };

struct Token {
  Kind kind;
  std::string text;
};

class Parser {
 public:
  Parser(const std::string& text, const std::string& where) : text_(text), where_(where) { tokenize(); }

  CheckedCriterion parse() {
    disjunction();
    if (peek().kind != Kind::End) fail(fmt::format("unexpected '{}'", peek().text));
    return {out_, names_};
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw ConfigError(fmt::format("{}: criterion '{}': {}; {}", where_, text_, problem, kAllowed));
  }

  void tokenize() {
    std::size_t i = 0;
    while (i < text_.size()) {
      const char c = text_[i];
      if (std::isspace(static_cast<unsigned char>(c))) {
        ++i;
      } else if (std::isdigit(static_cast<unsigned char>(c)) || (c == '.' && i + 1 < text_.size() &&
                                                                  std::isdigit(static_cast<unsigned char>(text_[i + 1])))) {
        i = number(i);
      } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
        std::size_t end = i;
        while (end < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[end])) || text_[end] == '_')) ++end;
        tokens_.push_back({Kind::Name, text_.substr(i, end - i)});
        i = end;
      } else {
        i = symbol(i);
      }
    }
    tokens_.push_back({Kind::End, "end of text"});
  }

  std::size_t number(std::size_t i) {
    const char* begin = text_.c_str() + i;
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(begin, &end);
    const std::string literal(begin, static_cast<std::size_t>(end - begin));
    if (literal.find_first_of("xXnN") != std::string::npos) fail(fmt::format("'{}' is not a decimal number", literal));
    if (errno == ERANGE || !std::isfinite(value)) {
      fail(fmt::format("the number {} is out of range (a finite double, |x| < 1.8e308, not a denormal)", literal));
    }
    tokens_.push_back({Kind::Number, literal});
    return i + literal.size();
  }

  std::size_t symbol(std::size_t i) {
    static const std::vector<std::string> symbols = {"<=", ">=", "==", "!=", "&&", "||", "<", ">", "=", "!",
                                                     "+",  "-",  "*",  "/",  "^",  "(",  ")", ",", "?", ":"};
    for (const auto& symbol : symbols) {
      if (text_.compare(i, symbol.size(), symbol) == 0) {
        tokens_.push_back({Kind::Operator, symbol});
        return i + symbol.size();
      }
    }
    fail(fmt::format("unexpected character '{}'", text_[i]));
  }

  const Token& peek(std::size_t ahead = 0) const { return tokens_[std::min(pos_ + ahead, tokens_.size() - 1)]; }
  bool isOperator(const char* symbol) const { return peek().kind == Kind::Operator && peek().text == symbol; }
  bool isComparison() const { return isOperator("<") || isOperator("<=") || isOperator(">") || isOperator(">="); }
  bool isArithmeticOperator() const {
    return isOperator("+") || isOperator("-") || isOperator("*") || isOperator("/") || isOperator("^");
  }

  void emit(const std::string& text) { out_ += text; }

  /// 'and' / 'or' (or their old spellings); true if one was consumed.
  bool connective(const char* word, const char* old_spelling) {
    if (peek().kind == Kind::Name && peek().text == word) {
      ++pos_;
      return true;
    }
    if (isOperator(old_spelling)) {
      deprecated(old_spelling, word);
      ++pos_;
      return true;
    }
    return false;
  }

  void deprecated(const std::string& old_spelling, const std::string& word) const {
    static std::mutex mutex;
    static std::set<std::string> said;
    const std::lock_guard<std::mutex> lock(mutex);
    if (said.insert(text_).second) {
      spdlog::warn("{}: criterion '{}': '{}' is deprecated; write '{}' (the old spelling still works for now)", where_,
                   text_, old_spelling, word);
    }
  }

  void disjunction() {
    conjunction();
    while (connective("or", "||")) {
      emit(" || ");
      conjunction();
    }
  }

  void conjunction() {
    atom();
    while (connective("and", "&&")) {
      emit(" && ");
      atom();
    }
  }

  /// A parenthesised criterion, or a comparison (whose left side may start with a parenthesis).
  void atom() {
    if (isOperator("(")) {
      const std::size_t pos = pos_;
      const std::string out = out_;
      const std::size_t names = names_.size();
      try {
        ++pos_;
        emit("(");
        disjunction();
        if (!isOperator(")")) fail(fmt::format("expected ')' before '{}'", peek().text));
        ++pos_;
        emit(")");
        if (!isComparison() && !isArithmeticOperator()) return;
      } catch (const ConfigError&) {
      }
      pos_ = pos;  // it was arithmetic: `(d_min + 1) < 2`
      out_ = out;
      names_.resize(names);
    }
    comparison();
  }

  void comparison() {
    const std::size_t start = pos_;
    arithmetic();
    if (isOperator("=")) fail("'=' is not a comparison (it assigns); use <, <=, > or >=");
    if (isOperator("==") || isOperator("!=")) {
      fail(fmt::format("'{}' is not allowed (metrics are real numbers; compare with <, <=, > or >=)", peek().text));
    }
    if (!isComparison()) {
      const std::string side = describeFrom(start);
      if (peek().kind == Kind::End) fail(fmt::format("'{}' is not a comparison", side));
      fail(fmt::format("'{}' is not a comparison (unexpected '{}' after it)", side, peek().text));
    }
    emit(" " + peek().text + " ");
    ++pos_;
    arithmetic();
    if (isComparison()) fail("chained comparisons such as '1 < d_min < 2' are not allowed; write '1 < d_min and d_min < 2'");
  }

  std::string describeFrom(std::size_t start) const {
    std::string text;
    for (std::size_t i = start; i < pos_; ++i) text += (i == start ? "" : " ") + tokens_[i].text;
    return text;
  }

  void arithmetic() {
    term();
    while (isOperator("+") || isOperator("-")) {
      emit(peek().text);
      ++pos_;
      term();
    }
  }

  void term() {
    factor();
    while (isOperator("*") || isOperator("/")) {
      emit(peek().text);
      ++pos_;
      factor();
    }
  }

  void factor() {
    unary();
    if (isOperator("^")) {
      emit("^");
      ++pos_;
      factor();
    }
  }

  void unary() {
    if (isOperator("-") || isOperator("+")) {
      emit(peek().text);
      ++pos_;
      unary();
      return;
    }
    primary();
  }

  void primary() {
    const Token token = peek();
    if (token.kind == Kind::Number) {
      emit(token.text);
      ++pos_;
    } else if (token.kind == Kind::Name && (token.text == "and" || token.text == "or")) {
      fail(fmt::format("'{}' needs a comparison on each side", token.text));
    } else if (token.kind == Kind::Name) {
      ++pos_;
      emit(token.text);
      if (isOperator("(")) {
        call();
      } else if (std::find(names_.begin(), names_.end(), token.text) == names_.end()) {
        names_.push_back(token.text);
      }
    } else if (isOperator("(")) {
      ++pos_;
      emit("(");
      arithmetic();
      if (!isOperator(")")) fail(fmt::format("expected ')' before '{}'", peek().text));
      ++pos_;
      emit(")");
    } else {
      fail(token.kind == Kind::End ? std::string("it ends where a number or metric was expected")
                                   : fmt::format("unexpected '{}' where a number or metric was expected", token.text));
    }
  }

  /// A function's arguments (the only place a ',' is allowed).
  void call() {
    ++pos_;
    emit("(");
    arithmetic();
    while (isOperator(",")) {
      emit(",");
      ++pos_;
      arithmetic();
    }
    if (!isOperator(")")) fail(fmt::format("expected ')' before '{}'", peek().text));
    ++pos_;
    emit(")");
  }

  const std::string& text_;
  const std::string& where_;
  std::vector<Token> tokens_;
  std::size_t pos_ = 0;
  std::string out_;
  std::vector<std::string> names_;
};

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  const auto last = text.find_last_not_of(" \t");
  return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
}

}  // namespace

CheckedCriterion checkCriterion(const std::string& text, const std::string& where) {
  return Parser(text, where).parse();
}

NamedCriterion splitNamedCriterion(const std::string& text, const std::string& where) {
  NamedCriterion named;
  const auto colon = text.find(':');
  named.criterion = trimmed(colon == std::string::npos ? text : text.substr(colon + 1));
  named.name = colon == std::string::npos ? named.criterion : trimmed(text.substr(0, colon));
  if (named.name.empty() || named.criterion.empty()) {
    throw ConfigError(fmt::format("{}: got '{}', expected a criterion or 'name: criterion', e.g. 'd_min < 2' or "
                                  "'close: d_min < 2'",
                                  where, text));
  }
  return named;
}

}  // namespace vsd
