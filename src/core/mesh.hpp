// Geometry and texture look-ups on the textured mesh (tightex/mesh.hpp) that the stages share.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/image.hpp"
#include "tightex/mesh.hpp"

namespace tightex {

/// Texels the input gives triangle t: its UV area (after -s/-o) times its texture's size; 0 without a
/// texture or when the texture's size is unknown.
double input_texel_area(const TexturedMesh& mesh, size_t t);

/// The texture detail of input triangle t: the root mean square colour gradient of its texture over
/// the triangle, in 8-bit levels (RGB, summed over channels) per unit of 3D length, from central
/// differences one input texel apart at up to 15 points spread over the triangle; with the other maps
/// the material binds (Material::maps, each slot over the channels it reads, in its own texels, scaled
/// to three channels), the root of the sum of their squared details. 0 where the triangle
/// has no loaded texture or no area. Under the usual model of reconstruction error (a region sampled
/// with texel spacing h loses about |gradient|^2 h^2 per unit area), the texel density that minimises
/// the error over the surface for a fixed budget is proportional to this (Sander et al. 2002,
/// signal-specialized parametrization).
double input_detail(const TexturedMesh& mesh, size_t t);

/// The texture triangle t samples (its material's), or -1 without a material or texture.
int texture_of(const TexturedMesh& m, size_t t);

/// The loaded texture image triangle t samples; nullptr without a material, texture or pixels.
const Image* image_of(const TexturedMesh& m, size_t t);

/// 3D area of a triangle.
double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c);
/// 3D area of the triangle `t` (three indices into `positions`).
inline double triangle_area(const std::vector<Vec3>& positions, const Tri& t) {
  return triangle_area(positions[t[0]], positions[t[1]], positions[t[2]]);
}
/// Signed area of a 2D triangle (positive = counter-clockwise).
double signed_area(const Vec2& a, const Vec2& b, const Vec2& c);

}  // namespace tightex
