#pragma once
// A decoder written by a test, as a newcomer would write one (docs/design.md "Adding a
// surrogate, a decoder, a controller, a map importer").
#include "../../../src/model/decoder.hpp"

namespace vsd::test {

/// "constant_accel": one acceleration per scene; the Ego moves along its initial heading
/// at that constant acceleration (x = v t + a t^2 / 2). Trained on ADE.
model::DecoderEntry constantAccelDecoderEntry();

}  // namespace vsd::test
