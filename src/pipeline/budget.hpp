// The texture's budget and shape: how many texels, in what width and height.
#pragma once
#include <utility>
#include <vector>

namespace tightex {

/// W x H for a texture of about size^2 texels whose width/height is `aspect`: W a multiple of 4 near
/// size x sqrt(aspect), H the least multiple of 4 with W x H >= size^2 (never fewer texels than the
/// square); size x size for 1.
std::pair<int, int> atlas_size(int size, double aspect);

/// The default budget's atlas side for components of these areas: `size` where it holds a 4 x 4
/// rectangle for every component, else the side that holds size^2 texels and 16 more per component,
/// grown by 10% steps until the layout holds them (not beyond max(size, kDefaultSizeMax)).
int atlas_side_holding(const std::vector<double>& areas, int size);

/// The per-component layout's largest side for the default budget: `size` shrunk by the square root of
/// the largest component's share, so all the textures together hold about size^2 texels.
int per_component_side(const std::vector<double>& shares, int size);

}  // namespace tightex
