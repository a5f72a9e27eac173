#pragma once
// pugixml helpers shared by the OpenDRIVE and OpenSCENARIO readers and writers
// (private to the interop module).
//
// Writing: numbers in their shortest exact form (so a reader gets the very same
// double back), documents saved atomically.
// Reading: every message names the file, the line, the element and what was
// expected; elements outside the supported subset are refused by name.

#include <pugixml.hpp>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"

namespace vsd::interop::xml {

/// Shortest text that parses back to exactly `value` ("0.2", "12.5", "-1e-05").
std::string number(double value);

/// Appends <name> to `parent` with the attributes in the given order.
pugi::xml_node child(pugi::xml_node parent, const char* name,
                     std::initializer_list<std::pair<const char*, std::string>> attributes = {});

/// The document as text (2-space indentation, UTF-8 declaration).
std::string toText(const pugi::xml_document& document);
/// Writes the document under a temporary name and renames it into place.
void save(const pugi::xml_document& document, const std::filesystem::path& file);

/// A parsed file that remembers where its elements are. Attribute values of the
/// form `$name` are replaced by the parameter `name`, and `${...}` by the value of the
/// expression (OpenSCENARIO parameters, osc_expression.hpp).
class Reader {
 public:
  /// Reads at most `limit` bytes of a regular file (core/files.hpp). Throws ConfigError
  /// "file:line: not well-formed XML (...)" or IoError.
  Reader(const std::filesystem::path& file, const ReadLimit& limit);
  /// Parses `text` as if it were `file` (messages name `file`).
  Reader(const std::filesystem::path& file, std::string text);

  const pugi::xml_document& document() const { return document_; }
  pugi::xml_node root() const { return document_.document_element(); }
  const std::filesystem::path& file() const { return file_; }

  /// 1-based line of an element in the file.
  int line(const pugi::xml_node& node) const;
  /// "file:line: <element>" for messages.
  std::string where(const pugi::xml_node& node) const;

  /// Parameter values for `$name` references (OpenSCENARIO ParameterDeclarations).
  void setParameters(std::map<std::string, std::string> parameters) { parameters_ = std::move(parameters); }
  const std::map<std::string, std::string>& parameters() const { return parameters_; }

  /// An attribute's text with parameters resolved; throws ConfigError if absent.
  std::string text(const pugi::xml_node& node, const char* attribute) const;
  std::optional<std::string> optionalText(const pugi::xml_node& node, const char* attribute) const;
  /// An attribute as a finite number within `range` (vsd/core/numbers.hpp: NaN,
  /// infinities, overflow refused by name); throws ConfigError naming element, attribute, value.
  double number(const pugi::xml_node& node, const char* attribute, const NumberRange& range = NumberRange::any()) const;
  std::optional<double> optionalNumber(const pugi::xml_node& node, const char* attribute,
                                       const NumberRange& range = NumberRange::any()) const;
  /// An attribute as a whole number min .. max (no fraction, no wrap-around).
  std::int64_t integer(const pugi::xml_node& node, const char* attribute, std::int64_t min, std::int64_t max) const;
  /// An attribute that must be one of `allowed`.
  std::string oneOf(const pugi::xml_node& node, const char* attribute, std::initializer_list<const char*> allowed) const;
  /// An xsd:boolean attribute ("true", "false", "1", "0"; any other value refused by name);
  /// std::nullopt if absent.
  std::optional<bool> optionalBoolean(const pugi::xml_node& node, const char* attribute) const;
  /// A required xsd:boolean attribute (refused by name if missing or another value).
  bool boolean(const pugi::xml_node& node, const char* attribute) const;

  /// The single child element `name`; throws ConfigError if it is missing or repeated.
  pugi::xml_node only(const pugi::xml_node& parent, const char* name) const;
  /// Every child element must be named in `supported`; otherwise throws ConfigError
  /// "file:line: element <X> is outside the supported subset (here: a, b, c)".
  void requireSubset(const pugi::xml_node& parent, std::initializer_list<const char*> supported) const;
  /// The one child element of a choice (e.g. <Position>), after requireSubset.
  pugi::xml_node choice(const pugi::xml_node& parent, std::initializer_list<const char*> supported) const;

  /// ConfigError "file:line: <element>: message".
  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& message) const;

  /// Attributes read above (text, numbers, ...) are remembered, and so are the elements
  /// interpreted (an attribute read, or the children checked by requireSubset). An attribute
  /// of such an element that nothing read is outside the supported subset, unless it is left
  /// here on purpose: known and, as the caller says where it is read, not simulated.
  void leave(const pugi::xml_node& node, std::initializer_list<const char*> attributes) const;
  /// leave() for every attribute of `node` and the elements inside it (a part replaced whole).
  void leaveAll(const pugi::xml_node& node) const;
  /// "file:line: <element>: attribute a=\"v\" ..." for each attribute of an interpreted element
  /// that was neither read nor left, in document order. A `name` is always known: names
  /// identify elements, and references to them are read where they occur.
  std::vector<std::string> unreadAttributes() const;

 private:
  void parse();
  /// 1-based line of a byte offset of the text.
  int lineOfOffset(std::ptrdiff_t offset) const;
  /// Throws ConfigError for a document type that declares entities (billion laughs, XXE).
  void refuseEntityDeclarations() const;

  std::filesystem::path file_;
  std::string text_;
  std::vector<std::size_t> lineStarts_;
  pugi::xml_document document_;
  std::map<std::string, std::string> parameters_;
  // pugixml's node and attribute records, stable while the document lives.
  mutable std::unordered_set<const void*> interpreted_;
  mutable std::unordered_set<const void*> read_;
};

}  // namespace vsd::interop::xml
