#pragma once
// An OpenDRIVE road as the scenario language's arc road (private to the interop module).
//
// The scenario language (docs/scenario-language.md) has one kind of road an OpenDRIVE
// file can map onto exactly: a carriageway of equal driving lanes along a line or a
// circular arc. A file maps if it has one road whose plan view is lines or arcs of one
// curvature, one lane section, no lane offset, constant widths, and on its right side
// (negative lane ids, driven towards +s) a contiguous run of `driving` lanes of one
// width. Lanes between the reference line and that run and `shoulder`/`stop` lanes
// right of it become the language's shoulders; the left side (positive ids) is not
// part of vsd-sumo's road. Elevation, superelevation, road marks, links, objects and
// signals do not change the planar lanes: they are reported as not simulated.
//
// The language's road centre is the centre line of the driving lanes (t = centreT()),
// a concentric arc: its curvature is k / (1 - k * centreT()) and its s is the reference
// line's s times (1 - k * centreT()).

#include <filesystem>
#include <string>

#include "osc_findings.hpp"
#include "vsd/core/geometry.hpp"

namespace vsd::interop::osc {

struct CarriagewayRoad {
  std::filesystem::path file;
  std::string id;
  Vec2 start;               ///< m, start of the reference line
  double heading = 0.0;     ///< rad, of the reference line at s = 0
  double curvature = 0.0;   ///< 1/m of the reference line, > 0 left
  double length = 0.0;      ///< m of reference line
  int lanes = 0;            ///< driving lanes on the right side
  int innermostLaneId = -1; ///< OpenDRIVE id of the driving lane next to the reference line
  double laneWidth = 0.0;   ///< m
  double innerT = 0.0;      ///< m, t of the driving lanes' inner edge (<= 0)
  double shoulderLeft = 0.0;   ///< m between the reference line and the driving lanes
  double shoulderRight = 0.0;  ///< m of shoulder/stop lanes right of the driving lanes

  /// t of the driving lanes' centre line (the language's road centre).
  double centreT() const { return innerT - lanes * laneWidth / 2.0; }
  /// Language lane (0 = rightmost) of a driving lane id; throws ConfigError naming `where` otherwise.
  int languageLane(long lane_id, const std::string& where) const;
  /// t of a language lane's centre.
  double laneCentreT(int lane) const;
  /// The language lane whose centre is nearest to t (clamped to the driving lanes).
  int nearestLane(double t) const;
  /// Language s (along the driving lanes' centre line) of the reference line's s.
  double languageS(double s) const { return s * (1.0 - curvature * centreT()); }
  /// The language road's curvature (of the driving lanes' centre line).
  double languageCurvature() const { return curvature / (1.0 - curvature * centreT()); }
  /// Point at reference-line coordinates (s, t), and back.
  Vec2 point(double s, double t) const;
  /// Road heading (rad) at s.
  double headingAt(double s) const { return heading + curvature * s; }
  std::pair<double, double> coordinates(const Vec2& point) const;
};

/// Reads the road; refuses (ConfigError "file:line: <element>: why") what does not map.
/// Elements that do not change the planar lanes go to `findings` as notes.
CarriagewayRoad readCarriagewayRoad(const std::filesystem::path& file, Findings& findings);

}  // namespace vsd::interop::osc
