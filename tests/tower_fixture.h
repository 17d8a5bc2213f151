// SPDX-License-Identifier: BSD-3-Clause
//
// The rendered tower fixtures that several end-to-end tests share (built
// once per build of bayon, see SharedFixture).
#pragma once

#include <string>

namespace bayon {
namespace testing {

// A tower ring of 16 views at 1200 x 800 (`bayon synth --scene tower`,
// seed 2, supersampling 1), with Moravec features, ring matches with one
// neighbour each side and relative orientations: <dir>/ws with images/,
// gt/ and database.db.
std::string OrientedTowerFixture();

}  // namespace testing
}  // namespace bayon
