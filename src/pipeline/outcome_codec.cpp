#include "outcome_codec.hpp"

#include "vsd/core/bytes.hpp"
#include "vsd/core/error.hpp"

namespace vsd::pipeline {

namespace {

void putPolyline(ByteWriter& writer, const Polyline& points) {
  std::vector<double> flat;
  flat.reserve(points.size() * 2);
  for (const auto& p : points) {
    flat.push_back(p.x());
    flat.push_back(p.y());
  }
  writer.putVector(flat);
}

Polyline getPolyline(ByteReader& reader) {
  const auto flat = reader.getVector<double>();
  Polyline points;
  points.reserve(flat.size() / 2);
  for (std::size_t i = 0; i + 1 < flat.size(); i += 2) points.emplace_back(flat[i], flat[i + 1]);
  return points;
}

}  // namespace

std::vector<char> encodeOutcomes(const std::vector<ScenarioOutcome>& outcomes) {
  ByteWriter writer;
  writer.put<std::uint64_t>(outcomes.size());
  for (const auto& outcome : outcomes) {
    writer.put<std::uint64_t>(outcome.index);
    writer.putVector(outcome.inputs);
    writer.putVector(outcome.metrics);
    writer.putString(outcome.failure);
    writer.put<std::int32_t>(outcome.egoLane);
    writer.putVector(outcome.referenceMetrics);
    writer.putString(outcome.referenceFailure);
    writer.put<double>(outcome.trace.step);
    writer.put<std::uint64_t>(outcome.trace.vehicles.size());
    for (const auto& track : outcome.trace.vehicles) {
      writer.putString(track.id);
      writer.put<VehicleRole>(track.role);
      writer.put<double>(track.length);
      writer.put<double>(track.width);
      writer.put<RoadUserType>(track.type);
      writer.putVector(track.states);
      writer.putVector(track.valid);
    }
    writer.put<std::uint64_t>(outcome.lanes.size());
    for (const auto& lane : outcome.lanes) {
      writer.putString(lane.id);
      writer.put<double>(lane.width);
      putPolyline(writer, lane.centre);
    }
  }
  return std::move(writer.bytes());
}

std::vector<ScenarioOutcome> decodeOutcomes(const std::vector<char>& bytes) {
  ByteReader reader(bytes);
  std::vector<ScenarioOutcome> outcomes(static_cast<std::size_t>(reader.get<std::uint64_t>()));
  for (auto& outcome : outcomes) {
    outcome.index = reader.get<std::uint64_t>();
    outcome.inputs = reader.getVector<double>();
    outcome.metrics = reader.getVector<double>();
    outcome.failure = reader.getString();
    outcome.egoLane = reader.get<std::int32_t>();
    outcome.referenceMetrics = reader.getVector<double>();
    outcome.referenceFailure = reader.getString();
    outcome.trace.step = reader.get<double>();
    outcome.trace.vehicles.resize(static_cast<std::size_t>(reader.get<std::uint64_t>()));
    for (auto& track : outcome.trace.vehicles) {
      track.id = reader.getString();
      track.role = reader.get<VehicleRole>();
      track.length = reader.get<double>();
      track.width = reader.get<double>();
      track.type = reader.get<RoadUserType>();
      if (static_cast<std::size_t>(track.type) >= roadUserKinds().size()) throw Error("internal: corrupt outcome message");
      track.states = reader.getVector<VehicleState>();
      track.valid = reader.getVector<std::uint8_t>();
    }
    outcome.lanes.resize(static_cast<std::size_t>(reader.get<std::uint64_t>()));
    for (auto& lane : outcome.lanes) {
      lane.id = reader.getString();
      lane.width = reader.get<double>();
      lane.centre = getPolyline(reader);
    }
  }
  return outcomes;
}

std::size_t passThroughWorkerPipe(const std::vector<ScenarioOutcome>& outcomes) {
  const auto message = encodeOutcomes(outcomes);
  if (decodeOutcomes(message).size() != outcomes.size()) throw Error("internal: outcome codec lost scenarios");
  return message.size();
}

}  // namespace vsd::pipeline
