#pragma once
#include "../decoder.hpp"

namespace vsd::model {
/// Registry entry of the `offsets` decoder.
DecoderEntry offsetsDecoderEntry();
}  // namespace vsd::model
