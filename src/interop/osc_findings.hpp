#pragma once
// What an OpenSCENARIO import made of each element (private to the interop module).
//
// One code path serves `vsd-sumo run` and `vsd-sumo scenario check`: the readers report
// every element they map (and onto what), every deviation from the file, and every
// refusal. A run stops at the first refusal (ConfigError, one line); a check collects
// them all and goes on with the next element.

#include <string>
#include <utility>
#include <vector>

#include "vsd/core/error.hpp"

namespace vsd::interop::osc {

/// An element that cannot be read because one it depends on was refused already (an entity
/// whose catalog entry was refused, named by a position or an Action): a check records nothing
/// more for it, so that one mistake is one line.
class FollowsARefusal : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

class Findings {
 public:
  enum class Kind { Mapped, Note, Refused };
  struct Line {
    Kind kind;
    std::string text;  ///< "file:line: <Element>: ..."
    /// A note `run` prints as a warning (once per run), as it matters to what is simulated.
    bool warn = false;
  };

  /// `collect`: record refusals and go on (scenario check); else throw at the first.
  explicit Findings(bool collect) : collect_(collect) {}

  /// A supported element and what it became.
  void mapped(const std::string& where, const std::string& what) {
    lines_.push_back({Kind::Mapped, where + ": " + what, false});
  }
  /// Supported, but not exactly as the file says (or not simulated at all): said once, here.
  /// A note already made (the same place and words: a condition translated again for another
  /// Event) is not repeated.
  /// `warn`: one that matters to what is simulated, which `run` prints as a warning.
  void note(const std::string& where, const std::string& what, bool warn = false) {
    std::string text = where + ": " + what;
    for (const Line& line : lines_) {
      if (line.kind == Kind::Note && line.text == text) return;
    }
    lines_.push_back({Kind::Note, std::move(text), warn});
  }
  /// A refusal: ConfigError now (run), or recorded (check) once (an element translated again
  /// for another Event refuses the same way).
  void refuse(const std::string& message) {
    if (!collect_) throw ConfigError(message);
    for (const Line& line : lines_) {
      if (line.kind == Kind::Refused && line.text == message) return;
    }
    lines_.push_back({Kind::Refused, message, false});
  }
  /// Runs `read`; a ConfigError it throws becomes a refusal. Returns false if it threw.
  template <class Read>
  bool attempt(Read&& read) {
    try {
      read();
      return true;
    } catch (const FollowsARefusal&) {
      if (!collect_) throw;  // only a check goes on after a refusal; a run never gets here
      return false;
    } catch (const ConfigError& error) {
      refuse(error.what());
      return false;
    }
  }

  /// Adds lines another Findings recorded (a refusal as refuse() would).
  void replay(const std::vector<Line>& lines) {
    for (const auto& line : lines) {
      if (line.kind == Kind::Refused) refuse(line.text);
      else lines_.push_back(line);
    }
  }

  bool collecting() const { return collect_; }
  bool anyRefused() const {
    for (const auto& line : lines_) {
      if (line.kind == Kind::Refused) return true;
    }
    return false;
  }
  const std::vector<Line>& lines() const { return lines_; }

 private:
  bool collect_;
  std::vector<Line> lines_;
};

}  // namespace vsd::interop::osc
