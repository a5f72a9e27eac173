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
#include <optional>
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

/// Lane attributes of every generated road that forbid SUMO's own lane changes to every
/// vehicle class vsd-sumo uses ("custom1" is none of them). vsd-sumo places each road user
/// itself (moveToXY, lane-change mode 0), so SUMO never changes lanes for them anyway; with
/// these SUMO's lane changer skips the lane-change model of every vehicle in every step.
/// (sumo-gui draws the lane markings solid.)
inline constexpr const char* kNoSumoLaneChanges = "changeLeft=\"custom1\" changeRight=\"custom1\"";

/// SUMO ids of sample `index`: edge "s<index>", its lanes "s<index>_<lane>".
std::string edgeIdFor(std::uint64_t index);

/// Sets SUMO_HOME to /usr/share/sumo when unset (SUMO needs its data files:
/// XML schemas, OpenDRIVE type maps).
void ensureSumoHome();

/// How the SUMO network of generated roads is built.
enum class NetWriter {
  Direct,      ///< vsd-sumo writes the .net.xml itself (NetworkBuilder::writeSumoNet): no extra process
  Netconvert,  ///< plain XML + a netconvert process (needed for extra netconvert options)
};
/// "direct" or "netconvert"; throws ConfigError naming `where`, the value and both names.
NetWriter parseNetWriter(const std::string& text, const std::string& where);
std::string netWriterName(NetWriter writer);

/// Roads collected for one network.
class NetworkBuilder {
 public:
  void add(std::uint64_t index, const RoadGeometry& road, const Vec2& offset);
  std::size_t size() const { return roads_.size(); }
  bool empty() const { return roads_.empty(); }
  /// Writes `<stem>.nod.xml` and `<stem>.edg.xml` (netconvert plain XML).
  void writePlainXml(const std::filesystem::path& stem) const;
  /// Writes `<stem>.net.xml` directly and returns its path: the network netconvert
  /// builds from writePlainXml's files with baseNetconvertOptions() — the same edges,
  /// lanes (shapes offset from the edge shape with SUMO's mitre rule, 0.01 m
  /// precision), widths, speeds, lengths and dead-end junctions; no connections
  /// (the roads are disjoint). Tested against netconvert's output. Throws IoError.
  std::filesystem::path writeSumoNet(const std::filesystem::path& stem) const;
  /// False if some lane's shape folds (a bend too sharp for its segment lengths and
  /// offset from the centre), where netconvert cuts lanes at the junctions in ways
  /// writeSumoNet does not reproduce, and roads whose lanes differ in width (netconvert's
  /// lane lengths there follow a rule of its own): such networks need netconvert.
  bool directlyWritable() const;
  /// The lanes of road `index` (added before) as SUMO loads them from a network built from
  /// these roads by netconvert or, in full detail, by writeSumoNet: ids, centre lines and
  /// widths, moved by -offset into the scenario frame. (writeSumoNet leaves out points of
  /// straight runs, which changes SUMO's positions along a lane by rounding only; vsd-sumo
  /// measures its lanes on these full-detail shapes.) Empty if the road is not in the builder.
  std::vector<LaneGeometry> lanesAsLoaded(std::uint64_t index) const;

 private:
  struct PlacedRoad {
    std::uint64_t index;
    RoadGeometry road;
    Vec2 offset;
    Polyline shape;  ///< edgeShape(road, offset), worked out once
  };
  /// The road centre in net coordinates as netconvert reads it from the plain XML
  /// (6 decimals), so both writers start from the same numbers.
  static Polyline edgeShape(const RoadGeometry& road, const Vec2& offset);
  static const Polyline& edgeShape(const PlacedRoad& placed) { return placed.shape; }
  std::vector<PlacedRoad> roads_;
};

/// A batch's network: being built by netconvert in the background, or already written.
class PendingNetwork {
 public:
  /// Starts netconvert on `<stem>.nod.xml` + `<stem>.edg.xml`; `extra_options` are
  /// appended to the command line.
  static PendingNetwork start(const std::filesystem::path& stem, const std::vector<std::string>& extra_options);
  /// A network that is complete already (written by NetworkBuilder::writeSumoNet).
  static PendingNetwork ready(const std::filesystem::path& net);
  /// Waits for netconvert (if any); returns the .net.xml. Throws SumoError naming the
  /// input files and netconvert's first error line.
  std::filesystem::path wait();

 private:
  PendingNetwork(std::optional<ChildProcess> process, std::filesystem::path stem, std::filesystem::path net)
      : process_(std::move(process)), stem_(std::move(stem)), net_(std::move(net)) {}
  std::optional<ChildProcess> process_;
  std::filesystem::path stem_;
  std::filesystem::path net_;
};

/// Where a converted OpenDRIVE map's coordinates start.
enum class OpenDriveOrigin {
  Normalised,  ///< netconvert's default: the network shifted to start at (0, 0) (maps)
  AsWritten,   ///< the file's own coordinates (a road compared with the one it was written from)
};

/// Converts an OpenDRIVE map to a SUMO network with netconvert (the "opendrive" entry of
/// MapImporterRegistry, src/road/importers/opendrive.cpp, and the OpenDRIVE import of
/// interop). Throws ConfigError for a missing file, SumoError "netconvert rejects FILE
/// (exit code N): first error line".
/// `extra`: further netconvert options (e.g. {"--flatten", "true"}: no elevation).
void convertOpenDrive(const std::filesystem::path& xodr, const std::filesystem::path& net,
                      OpenDriveOrigin origin = OpenDriveOrigin::Normalised, const std::vector<std::string>& extra = {});

/// Options this project always gives netconvert (net coordinates = generator coordinates, ...).
std::vector<std::string> baseNetconvertOptions();

}  // namespace vsd::road
