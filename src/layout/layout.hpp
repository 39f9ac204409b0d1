// Where each component's unit square goes in texture space.
#pragma once
#include <vector>

namespace tightex {

/// A rectangle of texels: columns [x, x+w), rows [y, y+h) (row 0 at the top of the image).
struct Rect {
  int image = 0;
  int x = 0, y = 0, w = 0, h = 0;
};

/// One texture of width x height shared by all components: each component gets a rectangle whose area
/// is proportional to its surface area and the rectangles tile the texture exactly, without a gap.
/// Method: recursive bisection (a slice-and-dice treemap): the components, largest first, are split
/// into two groups of nearly equal area and the rectangle is cut across its longer side in that
/// proportion, which keeps aspect ratios near 1. Every rectangle is at least min_side texels on each
/// side (a component too small for that still gets min_side x min_side: its share is rounded up).
/// Throws InputError when the texture cannot hold that many components.
std::vector<Rect> layout_atlas(const std::vector<double>& areas, int width, int height, int min_side = 4);

/// The paper's layout: one square image per component, the largest component `size` texels on a side
/// and the others scaled by the square root of their area share (at least min_side). Image i = component i.
std::vector<Rect> layout_per_component(const std::vector<double>& areas, int size, int min_side = 4);

}  // namespace tightex
