#pragma once
// A map importer written by a test, as a newcomer would write one (docs/design.md
// "Adding a surrogate, a decoder, a controller, a map importer").
#include "vsd/road/map_importers.hpp"

namespace vsd::test {

/// ".straight" files: one line "<length m> <lanes>", a straight road along +x from the origin.
road::MapImporter straightRoadImporter();

}  // namespace vsd::test
