#pragma once
// Many concrete scenarios share one SUMO network: each road is a separate edge
// placed in its own cell of a grid, so one netconvert call and one libsumo
// simulation serve a whole batch.
//
// A scenario's cell depends only on its sample index (never on the batch it is
// in), so SUMO computes with exactly the same net coordinates whatever --batch
// and --jobs are: outputs are bit-identical across batchings.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vsd/core/process.hpp"
#include "vsd/road/road_geometry.hpp"

namespace vsd::road {

class BatchLayout {
 public:
  static constexpr std::uint64_t kColumns = 64;
  static constexpr std::uint64_t kRows = 64;
  /// Largest batch whose cells are all distinct.
  static constexpr std::size_t kMaxBatch = kColumns * kRows;

  /// `cell_size`: m between neighbouring scenario origins (>= 100).
  explicit BatchLayout(double cell_size = 1000.0);

  /// A cell size for a logical scenario's roads: at least 1000 m, and large enough
  /// for the scenario region plus its straight extensions in any direction.
  static double cellSizeFor(const scenario::RoadSpec& road);

  /// Net-coordinate offset of scenario `sample_index`'s origin.
  Vec2 offsetFor(std::uint64_t sample_index) const;
  /// True if the road (scenario frame) stays inside its cell with a 25 m margin.
  bool fits(const RoadGeometry& road) const;
  double cellSize() const { return cellSize_; }

 private:
  double cellSize_;
};

/// SUMO ids of sample `index`: edge "s<index>", its lanes "s<index>_<lane>".
std::string edgeIdFor(std::uint64_t index);

/// Sets SUMO_HOME to /usr/share/sumo when unset (SUMO needs its data files:
/// XML schemas, OpenDRIVE type maps).
void ensureSumoHome();

/// Roads collected for one network.
class NetworkBuilder {
 public:
  void add(std::uint64_t index, const RoadGeometry& road, const Vec2& offset);
  std::size_t size() const { return roads_.size(); }
  bool empty() const { return roads_.empty(); }
  /// Writes `<stem>.nod.xml` and `<stem>.edg.xml` (netconvert plain XML).
  void writePlainXml(const std::filesystem::path& stem) const;

 private:
  struct PlacedRoad {
    std::uint64_t index;
    RoadGeometry road;
    Vec2 offset;
  };
  std::vector<PlacedRoad> roads_;
};

/// netconvert running in the background on `<stem>.nod.xml` + `<stem>.edg.xml`.
class PendingNetwork {
 public:
  /// Starts netconvert; `extra_options` are appended to the command line.
  static PendingNetwork start(const std::filesystem::path& stem, const std::vector<std::string>& extra_options);
  /// Waits for netconvert; returns `<stem>.net.xml`. Throws SumoError naming the
  /// input files and netconvert's first error line.
  std::filesystem::path wait();

 private:
  PendingNetwork(ChildProcess process, std::filesystem::path stem)
      : process_(std::move(process)), stem_(std::move(stem)) {}
  ChildProcess process_;
  std::filesystem::path stem_;
};

/// Converts an OpenDRIVE map to a SUMO network with netconvert. Throws SumoError
/// naming the file and netconvert's first error line.
void convertOpenDrive(const std::filesystem::path& xodr, const std::filesystem::path& net);

/// Options this project always gives netconvert (net coordinates = generator coordinates, ...).
std::vector<std::string> baseNetconvertOptions();

}  // namespace vsd::road
