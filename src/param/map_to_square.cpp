#include "param/map_to_square.hpp"

#include <optional>

#include "param/map_disk.hpp"
#include "param/multilevel.hpp"

namespace tightex {

std::vector<Vec2> map_to_square(const Disk& disk, const SquareMapOptions& options, SquareMapStats* stats) {
  SquareMapStats st;
  std::optional<std::vector<Vec2>> multilevel = multilevel_map(disk, options, st);
  std::vector<Vec2> uv = multilevel ? std::move(*multilevel) : map_disk(disk, options, st);
  if (stats) *stats = st;
  return uv;
}

}  // namespace tightex
