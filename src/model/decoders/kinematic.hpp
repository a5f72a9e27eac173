#pragma once
#include "../decoder.hpp"

namespace vsd::model {
/// Registry entry of the `kinematic` decoder.
DecoderEntry kinematicDecoderEntry();
}  // namespace vsd::model
