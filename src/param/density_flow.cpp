// Beyond the paper: a density-equalising flow (Gastner & Newman 2004, "Diffusion-based method for
// producing density-equalizing maps", PNAS 101:7499) in the map's own rectangle. The reweighted Tutte
// maps of map_to_square can only reach the densities a symmetric reweighting can express; where a
// region far from the boundary stays squeezed (the dancing girl with six patches of its surface
// missing: P5 of log2(area / target) -2.49 when the reweighting stalls), this flow moves the whole map
// until every region holds its target.
//
// The map's density rho = target / UV area is put on a grid over the rectangle; rho diffuses
// (d rho / dt = laplacian rho, zero flux through the rectangle's sides), which is solved exactly in
// the cosine basis; every vertex moves with the velocity -grad rho / rho, which carries each face's
// "population" (its target) along, so as rho tends to its mean every face tends to its target area.
// Zero flux means zero normal velocity on the sides: the boundary slides along them, the corners stay.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "param/param.hpp"

namespace tightex {

namespace {

using MatX = Eigen::MatrixXd;

}  // namespace

int flow_grid(size_t faces, const FlowOptions& options) {
  return options.grid > 0 ? options.grid : std::clamp(int(2 * std::sqrt(double(faces))), 32, 256);
}

FlowStats flow_density(const Surface& m, const std::vector<char>& fixed, const std::vector<double>& target, double aspect,
                       std::vector<Vec2>& uv, const FlowOptions& options, std::vector<Vec2>* tracers) {
  FlowStats st;
  const size_t nf = m.num_faces(), nv = m.num_vertices();
  if (nf == 0 || target.size() != nf || uv.size() != nv || !(aspect > 0)) return st;
  // The rectangle [0, lx] x [0, ly] of area 1, in the texture's proportions (texel spacing equal both
  // ways), so the flow moves texels isotropically.
  const double lx = std::sqrt(aspect), ly = 1 / lx;
  const int n = flow_grid(nf, options);
  const int nx = std::max(8, int(std::lround(n * lx))), ny = std::max(8, int(std::lround(n * ly)));
  const double hx = lx / nx, hy = ly / ny;
  // The points carried: the vertices, then the tracers.
  const size_t nt = tracers ? tracers->size() : 0, np = nv + nt;
  std::vector<Vec2> p(np);
  for (size_t v = 0; v < nv; ++v) p[v] = Vec2(uv[v].x() * lx, uv[v].y() * ly);
  for (size_t i = 0; i < nt; ++i) p[nv + i] = Vec2((*tracers)[i].x() * lx, (*tracers)[i].y() * ly);

  // The population: each face's target, scaled so the rectangle's mean density is 1, spread over the
  // cells by points on a lattice over the face (spaced at most half a cell), each split between the
  // four cells around it in proportion to its distance to their centres (cloud in cell): a face of
  // about a cell's size then adds a smooth bump, not a cell or nothing.
  double total_target = 0;
  for (size_t f = 0; f < nf; ++f)
    if (target[f] > 0 && std::isfinite(target[f])) total_target += target[f];
  if (!(total_target > 0)) return st;
  MatX rho0 = MatX::Zero(nx, ny);
  auto deposit = [&](const Vec2& g, double mass) {
    const double fx = std::clamp(g.x() - 0.5, 0.0, double(nx - 1)), fy = std::clamp(g.y() - 0.5, 0.0, double(ny - 1));
    const int i = std::min(nx - 2, int(fx)), j = std::min(ny - 2, int(fy));
    const double s = fx - i, u = fy - j;
    rho0(i, j) += (1 - s) * (1 - u) * mass;
    rho0(i + 1, j) += s * (1 - u) * mass;
    rho0(i, j + 1) += (1 - s) * u * mass;
    rho0(i + 1, j + 1) += s * u * mass;
  };
  for (size_t f = 0; f < nf; ++f) {
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
        deposit(a + (b - a) * ((i + 1.0 / 3) / k) + (c - a) * ((j + 1.0 / 3) / k), w);
        if (i + j + 1 < k) deposit(a + (b - a) * ((i + 2.0 / 3) / k) + (c - a) * ((j + 2.0 / 3) / k), w);
      }
  }

  // Cosine coefficients of rho0 (cell centres), and the bases at the grid's nodes (i h, i = 0..n),
  // where the velocity is interpolated from: the sine terms vanish on the sides, so the normal
  // velocity there is exactly 0.
  auto centre_basis = [](int cells_n) {
    MatX c(cells_n, cells_n);
    for (int i = 0; i < cells_n; ++i)
      for (int k = 0; k < cells_n; ++k) c(i, k) = std::cos(std::numbers::pi * k * (i + 0.5) / cells_n) * (k == 0 ? 1.0 : 2.0) / cells_n;
    return c;
  };
  const MatX coef = centre_basis(nx).transpose() * rho0 * centre_basis(ny);
  auto node_bases = [](int cells_n, double len, MatX& cos_b, MatX& dsin_b) {
    cos_b.resize(cells_n + 1, cells_n);
    dsin_b.resize(cells_n + 1, cells_n);
    for (int i = 0; i <= cells_n; ++i)
      for (int k = 0; k < cells_n; ++k) {
        const double w = std::numbers::pi * k / len, x = len * i / cells_n;
        cos_b(i, k) = std::cos(w * x);
        dsin_b(i, k) = (i == 0 || i == cells_n) ? 0.0 : -w * std::sin(w * x);
      }
  };
  MatX cx, sx, cy, sy;
  node_bases(nx, lx, cx, sx);
  node_bases(ny, ly, cy, sy);
  std::vector<double> wx2(nx), wy2(ny);
  for (int k = 0; k < nx; ++k) wx2[k] = std::pow(std::numbers::pi * k / lx, 2);
  for (int k = 0; k < ny; ++k) wy2[k] = std::pow(std::numbers::pi * k / ly, 2);

  // The velocity field at time t on the nodes; modes decayed below e^-36 are dropped.
  MatX vx(nx + 1, ny + 1), vy(nx + 1, ny + 1);
  double spread_now = 0;  // max |rho - 1| over the nodes at the last evaluation
  auto field = [&](double t) {
    int kx = nx, ky = ny;
    while (kx > 1 && wx2[kx - 1] * t > 36) --kx;
    while (ky > 1 && wy2[ky - 1] * t > 36) --ky;
    MatX a(kx, ky);
    for (int i = 0; i < kx; ++i)
      for (int j = 0; j < ky; ++j) a(i, j) = coef(i, j) * std::exp(-(wx2[i] + wy2[j]) * t);
    const MatX acy = a * cy.leftCols(ky).transpose(), asy = a * sy.leftCols(ky).transpose();
    const MatX r = cx.leftCols(kx) * acy, rx = sx.leftCols(kx) * acy, ry = cx.leftCols(kx) * asy;
    spread_now = 0;
    for (int i = 0; i <= nx; ++i)
      for (int j = 0; j <= ny; ++j) {
        const double rho = std::max(r(i, j), 1e-3);
        spread_now = std::max(spread_now, std::abs(r(i, j) - 1));
        vx(i, j) = -rx(i, j) / rho;
        vy(i, j) = -ry(i, j) / rho;
      }
  };
  auto velocity = [&](const Vec2& q) {
    const double fx = std::clamp(q.x() / hx, 0.0, double(nx)), fy = std::clamp(q.y() / hy, 0.0, double(ny));
    const int i = std::min(nx - 1, int(fx)), j = std::min(ny - 1, int(fy));
    const double s = fx - i, u = fy - j;
    auto lerp = [&](const MatX& g) {
      return (1 - s) * (1 - u) * g(i, j) + s * (1 - u) * g(i + 1, j) + (1 - s) * u * g(i, j + 1) + s * u * g(i + 1, j + 1);
    };
    return Vec2(lerp(vx), lerp(vy));
  };
  auto vertex_velocities = [&](const std::vector<Vec2>& at, std::vector<Vec2>& out) {
    double vmax = 0;
    for (size_t v = 0; v < np; ++v) {
      Vec2 w = velocity(at[v]);
      if (v < nv && (fixed[v] & 1)) w.x() = 0;
      if (v < nv && (fixed[v] & 2)) w.y() = 0;
      out[v] = w;
      vmax = std::max(vmax, w.norm());
    }
    return vmax;
  };
  std::vector<Vec2> v0(np), v1(np), q(np);
  // A step is taken only if every face keeps more than half its area (the flow is smooth: a face
  // halving in one step means the step was too long for it).
  std::vector<double> area(nf), trial_area(nf);
  for (size_t f = 0; f < nf && options.fold_free; ++f) area[f] = signed_area(p[m.triangles[f][0]], p[m.triangles[f][1]], p[m.triangles[f][2]]);
  auto acceptable = [&](const std::vector<Vec2>& q) {
    for (size_t f = 0; f < nf; ++f) {
      trial_area[f] = signed_area(q[m.triangles[f][0]], q[m.triangles[f][1]], q[m.triangles[f][2]]);
      if (area[f] > 0 && !(trial_area[f] > 0.5 * area[f])) return false;
    }
    area.swap(trial_area);
    return true;
  };
  const double h = std::min(hx, hy);
  // Starts blurred by options.start_cells: no ringing from the cells' jumps, and no finer detail than
  // the faces can follow.
  double t = options.start_cells * options.start_cells * h * h;
  const double t_end = options.time_scale * std::max(lx, ly) * std::max(lx, ly);
  double dt = 0;
  st.stopped = "time";
  while (t < t_end) {
    if (st.steps >= options.max_steps) {
      st.stopped = "steps";
      break;
    }
    field(t);
    if (spread_now < options.tolerance) {
      st.stopped = "converged";
      break;
    }
    const double vmax = vertex_velocities(p, v0);
    if (!(vmax > 0) || !std::isfinite(vmax)) {
      st.stopped = "converged";
      break;
    }
    // At most 0.3 cell a step, and at most 1.5 times the last step.
    double step = 0.3 * h / vmax;
    if (dt > 0) step = std::min(step, 1.5 * dt);
    step = std::min(step, t_end - t + 1e-12);
    bool taken = false;
    for (int tries = 0; tries < 30; ++tries, step *= 0.5) {
      // Heun: Euler predictor, trapezoid corrector.
      for (size_t v = 0; v < np; ++v) q[v] = p[v] + step * v0[v];
      field(t + step);
      vertex_velocities(q, v1);
      for (size_t v = 0; v < np; ++v) q[v] = p[v] + 0.5 * step * (v0[v] + v1[v]);
      if ((taken = !options.fold_free || acceptable(q))) break;
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
  auto back = [&](const std::vector<Vec2>& from, std::vector<Vec2>& to) {
    for (size_t v = 0; v < nv; ++v) {
      // Sides stay exactly on their lines (their normal velocity was zero; x * lx / lx may miss by an ulp).
      const Vec2 w(from[v].x() / lx, from[v].y() / ly);
      to[v] = Vec2((fixed[v] & 1) ? uv[v].x() : w.x(), (fixed[v] & 2) ? uv[v].y() : w.y());
    }
  };
  back(p, uv);
  for (size_t i = 0; i < nt; ++i) (*tracers)[i] = Vec2(p[nv + i].x() / lx, p[nv + i].y() / ly);
  return st;
}

}  // namespace tightex

