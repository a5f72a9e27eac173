#include "xml_support.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "osc_expression.hpp"

namespace fs = std::filesystem;

namespace vsd::interop::xml {

std::string number(double value) {
  if (value == 0.0) return "0";  // never "-0"
  return fmt::format("{}", value);
}

pugi::xml_node child(pugi::xml_node parent, const char* name,
                     std::initializer_list<std::pair<const char*, std::string>> attributes) {
  pugi::xml_node node = parent.append_child(name);
  for (const auto& [key, value] : attributes) node.append_attribute(key).set_value(value.c_str());
  return node;
}

std::string toText(const pugi::xml_document& document) {
  std::ostringstream stream;
  document.save(stream, "  ", pugi::format_default, pugi::encoding_utf8);
  return stream.str();
}

void save(const pugi::xml_document& document, const fs::path& file) { writeTextFileAtomically(file, toText(document)); }

Reader::Reader(const fs::path& file, const ReadLimit& limit) : file_(file), text_(readTextFile(file, limit)) { parse(); }

Reader::Reader(const fs::path& file, std::string text) : file_(file), text_(std::move(text)) { parse(); }

void Reader::parse() {
  lineStarts_.push_back(0);
  for (std::size_t i = 0; i < text_.size(); ++i) {
    if (text_[i] == '\n') lineStarts_.push_back(i + 1);
  }
  const auto result = document_.load_buffer(text_.data(), text_.size(),
                                            pugi::parse_default | pugi::parse_ws_pcdata_single | pugi::parse_doctype);
  if (!result) {
    throw ConfigError(fmt::format("{}:{}: not well-formed XML ({})", file_.string(), lineOfOffset(result.offset),
                                  result.description()));
  }
  refuseEntityDeclarations();
  if (!document_.document_element()) throw ConfigError(fmt::format("{}: no XML root element", file_.string()));
}

int Reader::lineOfOffset(std::ptrdiff_t offset) const {
  const auto it = std::upper_bound(lineStarts_.begin(), lineStarts_.end(), static_cast<std::size_t>(offset));
  return static_cast<int>(std::distance(lineStarts_.begin(), it));
}

void Reader::refuseEntityDeclarations() const {
  // pugixml expands no entities, but a file that declares them is written to attack the
  // reader of a DTD-expanding parser (billion laughs, external entities): OpenSCENARIO and
  // OpenDRIVE files need none, so it is refused rather than read with the names left in.
  for (const auto& node : document_.children()) {
    if (node.type() != pugi::node_doctype) continue;
    const std::string declaration = node.value();
    if (declaration.find("<!ENTITY") == std::string::npos) continue;
    throw ConfigError(fmt::format("{}:{}: the document type declares entities (<!ENTITY ...>); OpenSCENARIO and OpenDRIVE "
                                  "files need none, and vsd-sumo does not read files that do",
                                  file_.string(), line(node)));
  }
}

int Reader::line(const pugi::xml_node& node) const {
  const auto offset = node.offset_debug();
  if (offset < 0) return 0;
  const auto it = std::upper_bound(lineStarts_.begin(), lineStarts_.end(), static_cast<std::size_t>(offset));
  return static_cast<int>(std::distance(lineStarts_.begin(), it));
}

std::string Reader::where(const pugi::xml_node& node) const {
  return fmt::format("{}:{}: <{}>", file_.string(), line(node), node.name());
}

void Reader::fail(const pugi::xml_node& node, const std::string& message) const {
  throw ConfigError(fmt::format("{}: {}", where(node), message));
}

std::optional<std::string> Reader::optionalText(const pugi::xml_node& node, const char* attribute) const {
  interpreted_.insert(node.internal_object());
  const pugi::xml_attribute found = node.attribute(attribute);
  if (!found) return std::nullopt;
  read_.insert(found.internal_object());
  // "$name" and "${expression}" (OpenSCENARIO parameters); literal text otherwise.
  return osc::resolveValue(found.value(), parameters_, fmt::format("{}: attribute {}", where(node), attribute));
}

std::string Reader::text(const pugi::xml_node& node, const char* attribute) const {
  auto value = optionalText(node, attribute);
  if (!value) fail(node, fmt::format("attribute '{}' is missing", attribute));
  return *value;
}

std::optional<double> Reader::optionalNumber(const pugi::xml_node& node, const char* attribute,
                                             const NumberRange& range) const {
  const auto value = optionalText(node, attribute);
  if (!value) return std::nullopt;
  // XML Schema's xsd:double collapses surrounding white space; the number itself is read whole.
  const auto first = value->find_first_not_of(" \t\r\n");
  const auto last = value->find_last_not_of(" \t\r\n");
  const std::string trimmed = first == std::string::npos ? std::string() : value->substr(first, last - first + 1);
  return parseReal(trimmed, range, where(node), attribute);
}

double Reader::number(const pugi::xml_node& node, const char* attribute, const NumberRange& range) const {
  const auto value = optionalNumber(node, attribute, range);
  if (!value) fail(node, fmt::format("attribute '{}' is missing", attribute));
  return *value;
}

std::int64_t Reader::integer(const pugi::xml_node& node, const char* attribute, std::int64_t min, std::int64_t max) const {
  return parseInteger(text(node, attribute), min, max, where(node), attribute);
}

std::string Reader::oneOf(const pugi::xml_node& node, const char* attribute,
                          std::initializer_list<const char*> allowed) const {
  const std::string value = text(node, attribute);
  for (const char* candidate : allowed) {
    if (value == candidate) return value;
  }
  fail(node, fmt::format("attribute {}=\"{}\" is outside the supported subset (supported: {})", attribute, value,
                         fmt::join(allowed, ", ")));
}

std::optional<bool> Reader::optionalBoolean(const pugi::xml_node& node, const char* attribute) const {
  if (!node.attribute(attribute)) return std::nullopt;
  return boolean(node, attribute);
}

bool Reader::boolean(const pugi::xml_node& node, const char* attribute) const {
  const std::string value = oneOf(node, attribute, {"true", "false", "1", "0"});
  return value == "true" || value == "1";
}

void Reader::leave(const pugi::xml_node& node, std::initializer_list<const char*> attributes) const {
  for (const char* attribute : attributes) {
    if (const pugi::xml_attribute found = node.attribute(attribute)) read_.insert(found.internal_object());
  }
}

namespace {

/// Calls `visit` for `root` and every element inside it, without recursion (pugixml's walker
/// keeps its own stack: a hostile file may nest a million elements).
template <class Visit>
void forEachElement(const pugi::xml_node& root, Visit visit) {
  struct Walker : pugi::xml_tree_walker {
    explicit Walker(Visit& v) : visit(v) {}
    bool for_each(pugi::xml_node& node) override {
      if (node.type() == pugi::node_element) visit(node);
      return true;
    }
    Visit& visit;
  } walker(visit);
  visit(root);
  pugi::xml_node start = root;
  start.traverse(walker);
}

}  // namespace

void Reader::leaveAll(const pugi::xml_node& node) const {
  forEachElement(node, [&](const pugi::xml_node& element) {
    for (const pugi::xml_attribute& attribute : element.attributes()) read_.insert(attribute.internal_object());
  });
}

namespace {
/// Namespace declarations and XML Schema instance attributes (xsi:noNamespaceSchemaLocation) belong
/// to XML, not to the format read: they say nothing a simulation could follow or ignore.
bool xmlLevel(const std::string& name) {
  return name == "xmlns" || name.rfind("xmlns:", 0) == 0 || name.rfind("xsi:", 0) == 0;
}
}  // namespace

std::vector<std::string> Reader::unreadAttributes() const {
  std::vector<std::string> unread;
  forEachElement(root(), [&](const pugi::xml_node& node) {
    if (interpreted_.count(node.internal_object()) == 0) return;
    for (const pugi::xml_attribute& attribute : node.attributes()) {
      const std::string name = attribute.name();
      if (read_.count(attribute.internal_object()) > 0 || name == "name" || xmlLevel(name)) continue;
      unread.push_back(fmt::format("{}: attribute {}=\"{}\" is outside the supported subset (vsd-sumo does not "
                                   "read it)",
                                   where(node), attribute.name(), attribute.value()));
    }
  });
  return unread;
}

pugi::xml_node Reader::only(const pugi::xml_node& parent, const char* name) const {
  pugi::xml_node found;
  for (const pugi::xml_node& node : parent.children(name)) {
    if (found) fail(node, fmt::format("more than one <{}> in <{}> (the supported subset allows one)", name, parent.name()));
    found = node;
  }
  if (!found) fail(parent, fmt::format("expected a <{}> element", name));
  return found;
}

void Reader::requireSubset(const pugi::xml_node& parent, std::initializer_list<const char*> supported) const {
  interpreted_.insert(parent.internal_object());
  for (const pugi::xml_node& node : parent.children()) {
    if (node.type() != pugi::node_element) continue;
    const bool known = std::any_of(supported.begin(), supported.end(),
                                   [&](const char* name) { return std::string(node.name()) == name; });
    if (!known) {
      throw ConfigError(fmt::format("{}:{}: element <{}> is outside the supported subset (supported in <{}>: {})",
                                    file_.string(), line(node), node.name(), parent.name(),
                                    supported.size() == 0 ? std::string("nothing") : fmt::format("{}", fmt::join(supported, ", "))));
    }
  }
}

pugi::xml_node Reader::choice(const pugi::xml_node& parent, std::initializer_list<const char*> supported) const {
  requireSubset(parent, supported);
  pugi::xml_node found;
  for (const pugi::xml_node& node : parent.children()) {
    if (node.type() != pugi::node_element) continue;
    if (found) fail(node, fmt::format("<{}> holds more than one element (expected one of: {})", parent.name(),
                                      fmt::join(supported, ", ")));
    found = node;
  }
  if (!found) fail(parent, fmt::format("expected one of: {}", fmt::join(supported, ", ")));
  return found;
}

}  // namespace vsd::interop::xml
