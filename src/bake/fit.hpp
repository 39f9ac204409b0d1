// The least-squares fit of texels for bilinear read-back (beyond the paper's §4.3): a texture read back
// with bilinear filtering blurs once more what a point-sampled bake already blurred, so the fit chooses
// the texels whose bilinear reconstruction best matches the input (see BakeOptions::fit).
#pragma once
#include <cstdint>
#include <vector>

#include "bake/bake.hpp"
#include "bake/sampler.hpp"
#include "core/image.hpp"

namespace tightex {

/// A tile of an output image: columns [x0, x1), rows [y0, y1).
struct TexelTile {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

/// What the fit of one tile reads.
struct FitTileInput {
  const Image& base;                             // the plain bake of the whole image (after dilation)
  const std::vector<BakeTriangle>& triangles;    // all triangles of the bake
  const std::vector<TriangleSampler>& samplers;  // one per triangle of `nearby`, in its order
  const std::vector<uint32_t>& nearby;           // indices of the triangles that may reach the tile or its halo
};

/// The fit's halo: texels around a tile that are unknowns of its fit too (not written back), so that
/// the tile's border texels are fitted against samples on both sides.
constexpr int kFitHalo = 3;

/// Fits one tile of `out`: the texels of the tile and a halo of kFitHalo around it are unknowns,
/// starting from `input.base`; samples on a K x K grid in each texel that lies inside a nearby triangle
/// (and whose bilinear taps stay inside the region) get the footprint-filtered input colour. Minimises,
/// per channel, sum w_s (bilinear(c, s) - input(s))^2 + lambda |c - base|^2 by options.fit_iterations
/// steps of conjugate gradients; w_s is the 3D area per texel of the sample's triangle.
/// K and lambda are options.fit_samples and fit_lambda, or the defaults' where a nearby triangle's
/// footprint exceeds options.fit_fine_max_footprint.
/// Requires: `out` has the size of `input.base`; the tile lies inside it; `input.nearby` holds every
/// triangle that covers a texel within kFitHalo of the tile, each once, in ascending order.
/// Guarantees: writes the red, green and blue of the tile's own texels only (alpha and the halo are
/// left alone), so tiles can be fitted in parallel; leaves them as they are when no sample falls in
/// the region. Deterministic. Throws nothing but std::bad_alloc.
void fit_tile(const FitTileInput& input, const TexelTile& tile, const BakeOptions& options, Image& out);

}  // namespace tightex
