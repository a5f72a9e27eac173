#pragma once
// Physical defaults every module shares, each defined once here and passed on.
//
// These are the values a scenario (or a map export) starts from when its file gives
// none; the structs that carry them downstream take them from their source (the
// scenario, the dataset header, the model file), never from a default of their own.
// Road users' sizes live in the road-user table (vsd/core/road_user.hpp).

namespace vsd {

/// s: the simulation and sampling step (the paper's 0.2 s).
inline constexpr double kDefaultStep = 0.2;
/// s: the Ego future predicted and recorded (the paper's 5 s: 25 steps of kDefaultStep).
inline constexpr double kDefaultHorizon = 5.0;
/// m: a lane's width where a scenario or a map gives none (a motorway lane; ASAM's ALKS road).
inline constexpr double kDefaultLaneWidth = 3.5;

}  // namespace vsd
