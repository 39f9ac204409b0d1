// The density-equalising flow (density_flow.hpp) in the map's own rectangle. The reweighted Tutte
// maps of map_to_square can only reach the densities a symmetric reweighting can express; where a
// region far from the boundary stays squeezed, this flow moves the whole map until every region holds
// its target.
//
// The map's density rho = target / UV area is put on a grid over the rectangle; rho diffuses
// (d rho / dt = laplacian rho, zero flux through the rectangle's sides), which is solved exactly in
// the cosine basis; every vertex moves with the velocity -grad rho / rho, which carries each face's
// "population" (its target) along, so as rho tends to its mean every face tends to its target area.
// Zero flux means zero normal velocity on the sides: the boundary slides along them, the corners stay.
#include "param/density_flow.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace tightex {

namespace {

using MatX = Eigen::MatrixXd;

/// The rectangle [0, lx] x [0, ly] of area 1, in the texture's proportions (texel spacing equal both
/// ways, so the flow moves texels isotropically), cut into nx x ny cells of hx x hy.
struct FlowGrid {
  double lx = 1, ly = 1;
  int nx = 8, ny = 8;
  double hx = 1, hy = 1;

  FlowGrid(double aspect, int n) : lx(std::sqrt(aspect)), ly(1 / lx) {
    nx = std::max(8, int(std::lround(n * lx)));
    ny = std::max(8, int(std::lround(n * ly)));
    hx = lx / nx;
    hy = ly / ny;
  }
};

/// Adds `mass` at grid point g (in cells) to the four cells around it, in proportion to its distance
/// to their centres (cloud in cell).
void deposit(const FlowGrid& grid, const Vec2& g, double mass, MatX& rho) {
  const double fx = std::clamp(g.x() - 0.5, 0.0, double(grid.nx - 1)), fy = std::clamp(g.y() - 0.5, 0.0, double(grid.ny - 1));
  const int i = std::min(grid.nx - 2, int(fx)), j = std::min(grid.ny - 2, int(fy));
  const double s = fx - i, u = fy - j;
  rho(i, j) += (1 - s) * (1 - u) * mass;
  rho(i + 1, j) += s * (1 - u) * mass;
  rho(i, j + 1) += (1 - s) * u * mass;
  rho(i + 1, j + 1) += s * u * mass;
}

/// The population on the cells: each face's target, scaled so the rectangle's mean density is 1,
/// spread by points on a lattice over the face (spaced at most half a cell), each deposited into the
/// four cells around it: a face of about a cell's size then adds a smooth bump, not a cell or nothing.
/// `p`: the vertices in the rectangle. Requires total_target > 0.
MatX population(const Surface& m, const std::vector<double>& target, double total_target, const std::vector<Vec2>& p,
                const FlowGrid& grid) {
  MatX rho0 = MatX::Zero(grid.nx, grid.ny);
  const double hx = grid.hx, hy = grid.hy;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    if (!(target[f] > 0) || !std::isfinite(target[f])) continue;
    const double mass = target[f] / total_target / (hx * hy);  // density x cell area = mass
    const Tri& t = m.triangles[f];
    const Vec2 a(p[t[0]].x() / hx, p[t[0]].y() / hy), b(p[t[1]].x() / hx, p[t[1]].y() / hy), c(p[t[2]].x() / hx, p[t[2]].y() / hy);
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    // Each side cut in k (sub-triangles at most half a cell across; at most 64, so a sliver across the
    // whole grid costs 4096 points, not millions); the k^2 sub-triangles' centroids carry 1/k^2 each.
    const int k = longest < 32 ? std::max(1, int(std::ceil(2 * longest))) : 64;
    const double w = mass / double(k * k);
    for (int i = 0; i < k; ++i)
      for (int j = 0; i + j < k; ++j) {
        deposit(grid, a + (b - a) * ((i + 1.0 / 3) / k) + (c - a) * ((j + 1.0 / 3) / k), w, rho0);
        if (i + j + 1 < k) deposit(grid, a + (b - a) * ((i + 2.0 / 3) / k) + (c - a) * ((j + 2.0 / 3) / k), w, rho0);
      }
  }
  return rho0;
}

/// The cosine basis at the centres of n cells (rows: cells, columns: modes), scaled for the transform.
MatX centre_basis(int cells_n) {
  MatX c(cells_n, cells_n);
  for (int i = 0; i < cells_n; ++i)
    for (int k = 0; k < cells_n; ++k) c(i, k) = std::cos(std::numbers::pi * k * (i + 0.5) / cells_n) * (k == 0 ? 1.0 : 2.0) / cells_n;
  return c;
}

/// The cosine basis and its derivative at the grid's n + 1 nodes (i len / n): the sine terms vanish on
/// the sides, so the normal velocity there is exactly 0.
void node_bases(int cells_n, double len, MatX& cos_b, MatX& dsin_b) {
  cos_b.resize(cells_n + 1, cells_n);
  dsin_b.resize(cells_n + 1, cells_n);
  for (int i = 0; i <= cells_n; ++i)
    for (int k = 0; k < cells_n; ++k) {
      const double w = std::numbers::pi * k / len, x = len * i / cells_n;
      cos_b(i, k) = std::cos(w * x);
      dsin_b(i, k) = (i == 0 || i == cells_n) ? 0.0 : -w * std::sin(w * x);
    }
}

/// The diffusing density, exactly in the cosine basis, and the velocity -grad rho / rho it gives.
class VelocityField {
 public:
  double spread_now = 0;  // max |rho - 1| over the nodes at the last evaluate()

  VelocityField(const FlowGrid& grid, const MatX& rho0) : g_(grid), vx_(grid.nx + 1, grid.ny + 1), vy_(grid.nx + 1, grid.ny + 1) {
    coef_ = centre_basis(g_.nx).transpose() * rho0 * centre_basis(g_.ny);
    node_bases(g_.nx, g_.lx, cx_, sx_);
    node_bases(g_.ny, g_.ly, cy_, sy_);
    wx2_.resize(g_.nx);
    wy2_.resize(g_.ny);
    for (int k = 0; k < g_.nx; ++k) wx2_[k] = std::pow(std::numbers::pi * k / g_.lx, 2);
    for (int k = 0; k < g_.ny; ++k) wy2_[k] = std::pow(std::numbers::pi * k / g_.ly, 2);
  }

  /// The velocity on the nodes at time t; modes decayed below e^-36 are dropped.
  void evaluate(double t) {
    const int nx = g_.nx, ny = g_.ny;
    int kx = nx, ky = ny;
    while (kx > 1 && wx2_[kx - 1] * t > 36) --kx;
    while (ky > 1 && wy2_[ky - 1] * t > 36) --ky;
    MatX a(kx, ky);
    for (int i = 0; i < kx; ++i)
      for (int j = 0; j < ky; ++j) a(i, j) = coef_(i, j) * std::exp(-(wx2_[i] + wy2_[j]) * t);
    const MatX acy = a * cy_.leftCols(ky).transpose(), asy = a * sy_.leftCols(ky).transpose();
    const MatX r = cx_.leftCols(kx) * acy, rx = sx_.leftCols(kx) * acy, ry = cx_.leftCols(kx) * asy;
    spread_now = 0;
    for (int i = 0; i <= nx; ++i)
      for (int j = 0; j <= ny; ++j) {
        const double rho = std::max(r(i, j), 1e-3);
        spread_now = std::max(spread_now, std::abs(r(i, j) - 1));
        vx_(i, j) = -rx(i, j) / rho;
        vy_(i, j) = -ry(i, j) / rho;
      }
  }

  /// The last evaluated velocity at q, interpolated bilinearly between the nodes.
  Vec2 at(const Vec2& q) const {
    const double fx = std::clamp(q.x() / g_.hx, 0.0, double(g_.nx)), fy = std::clamp(q.y() / g_.hy, 0.0, double(g_.ny));
    const int i = std::min(g_.nx - 1, int(fx)), j = std::min(g_.ny - 1, int(fy));
    const double s = fx - i, u = fy - j;
    auto lerp = [&](const MatX& g) {
      return (1 - s) * (1 - u) * g(i, j) + s * (1 - u) * g(i + 1, j) + (1 - s) * u * g(i, j + 1) + s * u * g(i + 1, j + 1);
    };
    return Vec2(lerp(vx_), lerp(vy_));
  }

 private:
  const FlowGrid& g_;
  MatX coef_, cx_, sx_, cy_, sy_;
  std::vector<double> wx2_, wy2_;
  MatX vx_, vy_;
};

/// The velocity of every carried point (the first nv are vertices, their fixed coordinates held);
/// returns the largest speed.
double point_velocities(const VelocityField& field, const std::vector<char>& fixed, size_t nv, const std::vector<Vec2>& at,
                        std::vector<Vec2>& out) {
  double vmax = 0;
  for (size_t v = 0; v < at.size(); ++v) {
    Vec2 w = field.at(at[v]);
    if (v < nv && (fixed[v] & 1)) w.x() = 0;
    if (v < nv && (fixed[v] & 2)) w.y() = 0;
    out[v] = w;
    vmax = std::max(vmax, w.norm());
  }
  return vmax;
}

/// Accepts a step only if every face keeps more than half its area (the flow is smooth: a face
/// halving in one step means the step was too long for it).
class AreaGuard {
 public:
  AreaGuard(const Surface& m, const std::vector<Vec2>& p, bool active) : m_(m), area_(m.num_faces()), trial_area_(m.num_faces()) {
    for (size_t f = 0; f < m.num_faces() && active; ++f)
      area_[f] = signed_area(p[m.triangles[f][0]], p[m.triangles[f][1]], p[m.triangles[f][2]]);
  }
  /// Whether q keeps every face; if so, its areas become the reference.
  bool accept(const std::vector<Vec2>& q) {
    for (size_t f = 0; f < m_.num_faces(); ++f) {
      trial_area_[f] = signed_area(q[m_.triangles[f][0]], q[m_.triangles[f][1]], q[m_.triangles[f][2]]);
      if (area_[f] > 0 && !(trial_area_[f] > 0.5 * area_[f])) return false;
    }
    area_.swap(trial_area_);
    return true;
  }

 private:
  const Surface& m_;
  std::vector<double> area_, trial_area_;
};

/// Moves the points p (vertices then tracers, in the rectangle) with the field from its start time to
/// the end (Heun steps of at most 0.3 cell, at most 1.5 times the last, halved until the guard accepts).
void advance(const FlowGrid& grid, VelocityField& field, const std::vector<char>& fixed, size_t nv, const FlowOptions& options,
             AreaGuard& guard, std::vector<Vec2>& p, FlowStats& st) {
  const size_t np = p.size();
  std::vector<Vec2> v0(np), v1(np), q(np);
  const double h = std::min(grid.hx, grid.hy);
  // Starts blurred by options.start_cells: no ringing from the cells' jumps, and no finer detail than
  // the faces can follow.
  double t = options.start_cells * options.start_cells * h * h;
  const double t_end = options.time_scale * std::max(grid.lx, grid.ly) * std::max(grid.lx, grid.ly);
  double dt = 0;
  st.stopped = "time";
  while (t < t_end) {
    if (st.steps >= options.max_steps) {
      st.stopped = "steps";
      break;
    }
    field.evaluate(t);
    if (field.spread_now < options.tolerance) {
      st.stopped = "converged";
      break;
    }
    const double vmax = point_velocities(field, fixed, nv, p, v0);
    if (!(vmax > 0) || !std::isfinite(vmax)) {
      st.stopped = "converged";
      break;
    }
    double step = 0.3 * h / vmax;
    if (dt > 0) step = std::min(step, 1.5 * dt);
    step = std::min(step, t_end - t + 1e-12);
    bool taken = false;
    for (int tries = 0; tries < 30; ++tries, step *= 0.5) {
      // Heun: Euler predictor, trapezoid corrector.
      for (size_t v = 0; v < np; ++v) q[v] = p[v] + step * v0[v];
      field.evaluate(t + step);
      point_velocities(field, fixed, nv, q, v1);
      for (size_t v = 0; v < np; ++v) q[v] = p[v] + 0.5 * step * (v0[v] + v1[v]);
      if ((taken = !options.fold_free || guard.accept(q))) break;
    }
    if (!taken) {
      st.stopped = "fold";
      break;
    }
    p.swap(q);
    t += step;
    dt = step;
    ++st.steps;
  }
}

}  // namespace

int flow_grid(size_t faces, const FlowOptions& options) {
  return options.grid > 0 ? options.grid : std::clamp(int(2 * std::sqrt(double(faces))), 32, 256);
}

FlowStats flow_density(const Surface& m, const std::vector<char>& fixed, const std::vector<double>& target, double aspect,
                       std::vector<Vec2>& uv, const FlowOptions& options, std::vector<Vec2>* tracers) {
  FlowStats st;
  const size_t nf = m.num_faces(), nv = m.num_vertices();
  if (nf == 0 || target.size() != nf || uv.size() != nv || !(aspect > 0)) return st;
  const FlowGrid grid(aspect, flow_grid(nf, options));
  const double lx = grid.lx, ly = grid.ly;
  // The points carried: the vertices, then the tracers.
  const size_t nt = tracers ? tracers->size() : 0, np = nv + nt;
  std::vector<Vec2> p(np);
  for (size_t v = 0; v < nv; ++v) p[v] = Vec2(uv[v].x() * lx, uv[v].y() * ly);
  for (size_t i = 0; i < nt; ++i) p[nv + i] = Vec2((*tracers)[i].x() * lx, (*tracers)[i].y() * ly);

  double total_target = 0;
  for (size_t f = 0; f < nf; ++f)
    if (target[f] > 0 && std::isfinite(target[f])) total_target += target[f];
  if (!(total_target > 0)) return st;
  VelocityField field(grid, population(m, target, total_target, p, grid));
  AreaGuard guard(m, p, options.fold_free);
  advance(grid, field, fixed, nv, options, guard, p, st);

  for (size_t v = 0; v < nv; ++v) {
    // Sides stay exactly on their lines (their normal velocity was zero; x * lx / lx may miss by an ulp).
    const Vec2 w(p[v].x() / lx, p[v].y() / ly);
    uv[v] = Vec2((fixed[v] & 1) ? uv[v].x() : w.x(), (fixed[v] & 2) ? uv[v].y() : w.y());
  }
  for (size_t i = 0; i < nt; ++i) (*tracers)[i] = Vec2(p[nv + i].x() / lx, p[nv + i].y() / ly);
  return st;
}

}  // namespace tightex
