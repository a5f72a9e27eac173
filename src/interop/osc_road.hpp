#pragma once
// An OpenDRIVE road as one of the scenario language's roads (private to the interop module).
//
// A file maps if it has one road whose lane sections all have the same driving lanes and
// shoulders (lanes beyond them may differ), no lane offset, constant widths,
// and on the side driven along the reference line (towards +s) a contiguous run of
// `driving` lanes (each of its own width): the right side (negative lane ids) in right-hand
// traffic, the left side (positive ids) with rule="LHT". Lanes between the reference line
// and that run and `shoulder`/`stop` lanes beyond it become the language's shoulders; the
// other side is not part of vsd-sumo's road, with two exceptions in right-hand traffic:
// left driving lanes that continue the right side's across the reference line (no median)
// join the road where the scenario drives them along the reference line (joinLeftLanes),
// and the left side's run becomes the road instead of the right side's where the scenario
// drives it along the reference line (useLeftCarriageway; esmini's left-hand traffic "by
// heading"), or the left side's run driven against the reference line where the scenario
// drives it so (useReversedLeftCarriageway: the road is read on the reversed reference line,
// and the file's s, t, lane ids and offsets are turned with it: ownS, ownT, ownLaneId).
// Elevation, superelevation, road marks, road types and speeds, objects and signals do not
// change the planar lanes: they are reported as not simulated. A file of several roads gives the road the
// scenario names and the roads linked to it end to start, when they repeat its lanes.
//
// The plan view is any chain of `line`, `arc`, `spiral` and `paramPoly3` geometries.
// A road of one curvature (lines only, or arcs of one curvature) maps onto the language's
// arc road exactly, as closed formulas; any other becomes a polyline road, the centre
// line of its driving lanes sampled within 1 cm.
//
// The language's road centre is the centre line of the driving lanes (t = centreT()), a
// parallel curve of the reference line: along it, s advances by (1 - k(s) * centreT()) per m
// of reference line, so its s is s - centreT() * (heading turned since s = 0), and on
// roads of one curvature k its own curvature is k / (1 - k * centreT()).

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "osc_findings.hpp"
#include "xml_support.hpp"
#include "vsd/core/geometry.hpp"

namespace vsd::interop::osc {

/// One <geometry> of a plan view, placed by its own start, heading and length
/// (OpenDRIVE 1.6 section 7.3): a line, an arc, a spiral (curvature linear in s) or a
/// paramPoly3 (u, v cubic in p; p runs over [0, length] or, pRange="normalized", [0, 1]).
/// s along a paramPoly3 is its arc length (tabulated over p), stretched to the geometry's
/// length if the file's length differs from it.
class PlanGeometry {
 public:
  enum class Kind { Line, Arc, Spiral, ParamPoly3 };
  static PlanGeometry line(double s, const Vec2& start, double heading, double length);
  static PlanGeometry arc(double s, const Vec2& start, double heading, double length, double curvature);
  static PlanGeometry spiral(double s, const Vec2& start, double heading, double length, double curvature_start,
                             double curvature_end);
  /// u, v: coefficients a, b, c, d of the local u(p) and v(p).
  static PlanGeometry paramPoly3(double s, const Vec2& start, double heading, double length,
                                 const std::array<double, 4>& u, const std::array<double, 4>& v, bool normalized);

  Kind kind() const { return kind_; }
  double s() const { return s_; }            ///< m of reference line where it starts
  double length() const { return length_; }  ///< m
  /// Point ds m into the geometry (0 <= ds <= length).
  Vec2 point(double ds) const;
  /// rad: direction of travel ds m into the geometry.
  double heading(double ds) const;
  /// rad turned from the geometry's start to ds (unwrapped; a paramPoly3 within +-pi).
  double turn(double ds) const;
  /// 1/m, > 0 left, ds m into the geometry.
  double curvature(double ds) const;
  /// 1/m: the largest |curvature| along the geometry (sampled for paramPoly3).
  double largestCurvature() const;

 private:
  Vec2 localTangent(double p) const;
  Vec2 localSecond(double p) const;
  /// p of a paramPoly3 at ds m into it (by its arc length).
  double parameter(double ds) const;

  Kind kind_ = Kind::Line;
  double s_ = 0.0;
  Vec2 start_ = Vec2::Zero();
  double heading_ = 0.0;
  double length_ = 0.0;
  double curvatureStart_ = 0.0;
  double curvatureEnd_ = 0.0;
  std::array<double, 4> u_{};
  std::array<double, 4> v_{};
  bool normalized_ = false;
  double spiralStep_ = 0.0;          ///< m between the spiral's tabulated points
  std::vector<Vec2> spiralPoints_;   ///< the spiral's points at multiples of spiralStep_
  double parameterStep_ = 0.0;       ///< p between a paramPoly3's tabulated arc lengths
  std::vector<double> arcLengths_;   ///< m along a paramPoly3 at multiples of parameterStep_
};

/// A plan view's <geometry>; `offset`: m of a chain's reference line where its road starts (0: s
/// as in the file). Throws ConfigError naming the element for a shape or number outside the subset.
PlanGeometry readPlanGeometry(const xml::Reader& reader, const pugi::xml_node& geometry, double offset);

/// The heights of a road's <elevationProfile>: vsd-sumo is planar. Said in a note; where the road
/// rises or falls by kGradeThatMatters or more, the note is one `run` warns with: how far it
/// rises and falls and how steep it gets (z' sampled every 0.5 m of each record's stretch).
void noteElevation(const xml::Reader& reader, const pugi::xml_node& road, Findings& findings);

/// A run of driving lanes on one side of the reference line, as a carriageway driven along it.
struct DrivenRun {
  int innermostLaneId = -1;        ///< OpenDRIVE id of its driving lane next to the reference line
  std::vector<double> laneWidths;  ///< m, lane 0 (rightmost, driving along the reference line) first
  double innerShoulder = 0.0;      ///< m of lanes between the reference line and the run
  double outerShoulder = 0.0;      ///< m of shoulder/stop lanes beyond it
};

/// One OpenDRIVE road of the chain vsd-sumo's road is made of.
struct RoadPiece {
  std::string id;
  double start = 0.0;   ///< m of the chain's reference line where the road's s = 0 lies
  double length = 0.0;  ///< m of reference line
};

struct CarriagewayRoad {
  std::filesystem::path file;
  std::string id;  ///< the first road's
  /// The file's roads that make vsd-sumo's road, in driving order, linked end to start
  /// (successor and predecessor links outside junctions); one for a file of one road.
  std::vector<RoadPiece> pieces;
  std::vector<PlanGeometry> geometries;
  std::vector<double> turnBefore;  ///< rad turned along the reference line before each geometry
  bool oneCurvature = true;  ///< lines only, or arcs of one curvature: the language's arc road
  Vec2 start;               ///< m, start of the reference line
  double heading = 0.0;     ///< rad, of the reference line at s = 0
  double curvature = 0.0;   ///< 1/m of the reference line, > 0 left (roads of one curvature)
  double length = 0.0;      ///< m of reference line
  bool leftHandTraffic = false;  ///< rule="LHT": the left side is driven along the reference line
  /// The road is the left side's run (left-hand traffic, or useLeftCarriageway), else the right side's.
  bool leftCarriageway = false;
  /// The road is the left side's run driven against the reference line (right-hand traffic),
  /// read on the reversed reference line: its s runs from the file's road end (useReversedLeftCarriageway).
  bool reversed = false;
  int lanes = 0;            ///< the language's driving lanes: the run's (and the joined left ones)
  int innermostLaneId = -1; ///< OpenDRIVE id of the run's driving lane next to the reference line
  std::vector<double> laneWidths;  ///< m, each driving lane's, the language's lane 0 (rightmost) first
  /// m the lanes lie left of the reference line (OpenDRIVE's <laneOffset>, one constant along the
  /// road; > 0 left), in the road's own frame: negated on the reversed line. Part of innerT.
  double laneOffset = 0.0;
  /// m, t of the driving lanes' left edge (<= laneOffset; > laneOffset with joined left lanes)
  double innerT = 0.0;
  /// m left of the driving lanes (towards the reference line, or beyond joined left lanes)
  double shoulderLeft = 0.0;
  double shoulderRight = 0.0;  ///< m of shoulder/stop lanes right of the driving lanes
  MeasuredPolyline referenceSamples;  ///< the reference line within 1 mm (roads of several curvatures)
  std::vector<double> sampleS;        ///< m, reference-line s of each of referenceSamples' points
  /// "file:line: <left>" (or, in left-hand traffic, "<right>") of the lane section's side not
  /// driven along the reference line; empty: the road has none.
  std::string otherSide;
  /// Right-hand traffic: the left side's run as a carriageway of its own (useLeftCarriageway);
  /// none: leftRunProblem says why not (empty: there is no left side).
  std::optional<DrivenRun> leftRun;
  std::string leftRunProblem;
  /// Driving lanes of the left side (ids 1 .. adjoiningLeftLanes) that continue the right
  /// side's driving lanes across the reference line: lane -1 and lane 1 both driving.
  /// 0: none (a median, a lane the language cannot read, no left side).
  int adjoiningLeftLanes = 0;
  std::vector<double> adjoiningLeftWidths;  ///< m, of the adjoining left lanes, id 1 first
  double adjoiningLeftShoulder = 0.0;  ///< m of shoulder/stop lanes left of them
  bool leftLanesJoined = false;        ///< joinLeftLanes() was called
  /// "file:line: <laneSection>" of the first later section (or road of the chain) whose lanes
  /// left of the reference line differ from the first's; empty: they do not. Those lanes are not
  /// part of the road unless the scenario drives them (joinLeftLanes, useLeftCarriageway,
  /// useReversedLeftCarriageway refuse then).
  std::string leftSideChanges;

  /// Makes the adjoining left lanes the language's lanes `lanes` .. (leftmost last), driven
  /// along the reference line, and their shoulder/stop lanes its left shoulder. Only for a
  /// road with adjoining left lanes, once.
  void joinLeftLanes();
  /// Makes the left side's run the road instead of the right side's, driven along the
  /// reference line. Only in right-hand traffic with a leftRun, once, without joined lanes.
  void useLeftCarriageway();
  /// Makes the left side's run the road, driven against the reference line: the reference
  /// line is reversed (geometries in reverse order, each run backwards) and the left side
  /// becomes its right side. Only in right-hand traffic with a leftRun, once; throws ConfigError
  /// for a paramPoly3 geometry (not reversed).
  void useReversedLeftCarriageway();
  /// The road of the chain with this id; nullptr if it is not part of vsd-sumo's road.
  const RoadPiece* piece(const std::string& road_id) const;
  /// "road '7'", or "roads '1' -> '2'" for a chain, as messages name it.
  std::string name() const;
  /// Throws ConfigError naming leftSideChanges if the left side's lanes change along the road.
  void requireSteadyLeftSide() const;
  /// The file's s, t (or a lateral offset along t) and lane id on the road's own reference
  /// line: the same, or turned on a reversed road (length - s, -t, -id).
  double ownS(double file_s) const { return reversed ? length - file_s : file_s; }
  double ownT(double file_t) const { return reversed ? -file_t : file_t; }
  double ownDs(double file_ds) const { return reversed ? -file_ds : file_ds; }
  long ownLaneId(long file_id) const { return reversed ? -file_id : file_id; }
  /// Driving lanes of the right side.
  int rightLanes() const { return leftLanesJoined ? lanes - adjoiningLeftLanes : lanes; }
  /// rad, relative to the road's own reference line: the driving direction of the file's lane
  /// `lane_id` under the road's rule (0 along it, pi against it), which a relative
  /// <Orientation> counts from.
  double laneDirection(long lane_id) const;

  /// t of the driving lanes' centre line (the language's road centre).
  double centreT() const;
  /// True if every driving lane has the same width.
  bool oneLaneWidth() const;
  /// Language lane (0 = rightmost) of the file's driving lane id (with joined left lanes: id 1
  /// is the lane left of id -1); throws ConfigError naming `where` otherwise.
  int languageLane(long lane_id, const std::string& where) const;
  /// t of a language lane's centre.
  double laneCentreT(int lane) const;
  /// The language lane whose centre is nearest to t (clamped to the driving lanes).
  int nearestLane(double t) const;
  /// Language s (along the driving lanes' centre line) of the reference line's s.
  double languageS(double s) const;
  /// The language road's curvature (of the driving lanes' centre line; roads of one curvature).
  double languageCurvature() const { return curvature / (1.0 - curvature * centreT()); }
  /// 1/m: the reference line's curvature at s.
  double curvatureAt(double s) const;
  /// rad: turned along the reference line from s = 0 to s (unwrapped).
  double turnAt(double s) const;
  /// Point at reference-line coordinates (s, t), and back. Beyond the ends the road goes on
  /// along its end tangents.
  Vec2 point(double s, double t) const;
  /// Road heading (rad) at s.
  double headingAt(double s) const;
  std::pair<double, double> coordinates(const Vec2& point) const;

 private:
  const PlanGeometry& geometryAt(double s) const;
};

/// A scenario's first WorldPosition: `point` (m) and its heading `h` (rad) if it gives one.
struct WorldPlace {
  Vec2 point;
  std::optional<double> heading;
};

/// Reads the road; refuses (ConfigError "file:line: <element>: why") what does not map.
/// Elements that do not change the planar lanes go to `findings` as notes. In a file of
/// several roads, vsd-sumo's road is road `scenario_road` (the scenario's first roadId, which
/// `asked_where` names) — or, if the scenario names none, the road outside junctions whose lanes
/// hold `place` (the scenario's first WorldPosition, which `asked_where` names then) — with
/// the roads linked to it end to start; the others and the file's junctions are noted as not
/// simulated.
CarriagewayRoad readCarriagewayRoad(const std::filesystem::path& file, Findings& findings,
                                    const std::string& scenario_road = "", const std::string& asked_where = "",
                                    const std::optional<WorldPlace>& place = std::nullopt);

}  // namespace vsd::interop::osc
