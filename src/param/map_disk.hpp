// Steps 1-3 of the map of a disk onto the unit square (map_to_square), on the disk itself: what
// map_to_square runs on a small disk and multilevel_map on its coarse copy.
#pragma once
#include <vector>

#include "param/boundary.hpp"
#include "param/square_map_options.hpp"

namespace tightex {

/// Steps 1-3 of map_to_square on the disk itself (never multilevel). `placed` (optional) gets the
/// boundary's placement on the square (step 1). Same requirements, guarantees and throws.
std::vector<Vec2> map_disk(const Disk& disk, const SquareMapOptions& options, SquareMapStats& stats, SquareBoundary* placed = nullptr);

}  // namespace tightex
