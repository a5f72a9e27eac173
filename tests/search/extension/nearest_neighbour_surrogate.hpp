#pragma once
// A surrogate written by a test, as a newcomer would write one (docs/design.md "Adding a
// surrogate, a decoder, a controller, a map importer").
#include "vsd/search/surrogate.hpp"

namespace vsd::test {

/// "nearest-neighbour": a candidate is as likely critical (0.9) or not (0.1) as the
/// execution nearest to it in the normalised inputs.
search::SurrogateEntry nearestNeighbourSurrogate();

}  // namespace vsd::test
