// RasterizeFloorPlan: one pass over the triangles, three per-cell results, then a per-cell rule.
//  - band: a triangle clipped to min_z <= z <= max_z, projected on the xy plane (a convex polygon,
//    possibly flat: a vertical wall face projects to a segment), marks every cell it overlaps
//    (separating-axis test). Conservative, except that touching a cell's border within 0.1 mm
//    is not overlapping: geometry on a cell boundary (a wall face at x = 2.00 with 5 cm cells)
//    marks the cell it lies against on its own side of the boundary only through the solid rule
//    below, not the neighbour on the other side.
//  - floor: a roughly horizontal triangle (|n_z| >= 0.7 |n|) over the cell centre at a height in
//    [floor_min_z_m, min_z_m).
//  - solid: the first triangle above (cell centre, min_z_m) along +z, if it faces up (its back is
//    seen), the cell centre is inside a closed solid (a wall's core).
// Cell = obstacle if band or (fill_solids and solid); else free if floor; else outside.
#include "sim/floor_plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace voxplan {

namespace {

constexpr double kTouch_m = 1e-4;

using P2 = std::array<double, 2>;
using P3 = std::array<double, 3>;

// Sutherland-Hodgman against z >= z0 (keep_above) or z <= z0.
std::vector<P3> ClipZ(const std::vector<P3>& poly, double z0, bool keep_above) {
  std::vector<P3> out;
  const size_t n = poly.size();
  auto inside = [&](const P3& p) { return keep_above ? p[2] >= z0 : p[2] <= z0; };
  for (size_t i = 0; i < n; ++i) {
    const P3& a = poly[i];
    const P3& b = poly[(i + 1) % n];
    const bool ia = inside(a), ib = inside(b);
    if (ia) out.push_back(a);
    if (ia != ib) {
      const double t = (z0 - a[2]) / (b[2] - a[2]);
      out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), z0});
    }
  }
  return out;
}

struct Grid {
  double ox, oy, res;
  int w, h;
};

bool Overlaps(const std::vector<P2>& poly, double x0, double y0, double res) {
  double minx = poly[0][0], maxx = minx, miny = poly[0][1], maxy = miny;
  for (const P2& p : poly) {
    minx = std::min(minx, p[0]);
    maxx = std::max(maxx, p[0]);
    miny = std::min(miny, p[1]);
    maxy = std::max(maxy, p[1]);
  }
  if (maxx <= x0 + kTouch_m || minx >= x0 + res - kTouch_m) return false;
  if (maxy <= y0 + kTouch_m || miny >= y0 + res - kTouch_m) return false;
  const double cx = x0 + 0.5 * res, cy = y0 + 0.5 * res;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const P2& a = poly[i];
    const P2& b = poly[(i + 1) % n];
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    const double len = std::hypot(dx, dy);
    if (len < 1e-9) continue;
    const double nx = -dy / len, ny = dx / len;
    double pmin = std::numeric_limits<double>::infinity(), pmax = -pmin;
    for (const P2& p : poly) {
      const double d = nx * p[0] + ny * p[1];
      pmin = std::min(pmin, d);
      pmax = std::max(pmax, d);
    }
    const double c = nx * cx + ny * cy;
    const double r = 0.5 * res * (std::abs(nx) + std::abs(ny));
    if (pmax <= c - r + kTouch_m || pmin >= c + r - kTouch_m) return false;
  }
  return true;
}

void MarkBand(const std::vector<P2>& poly, const Grid& g, std::vector<uint8_t>* band) {
  double minx = poly[0][0], maxx = minx, miny = poly[0][1], maxy = miny;
  for (const P2& p : poly) {
    minx = std::min(minx, p[0]);
    maxx = std::max(maxx, p[0]);
    miny = std::min(miny, p[1]);
    maxy = std::max(maxy, p[1]);
  }
  const int ix0 = std::max(0, int(std::floor((minx - g.ox) / g.res)) - 1);
  const int ix1 = std::min(g.w - 1, int(std::floor((maxx - g.ox) / g.res)) + 1);
  const int iy0 = std::max(0, int(std::floor((miny - g.oy) / g.res)) - 1);
  const int iy1 = std::min(g.h - 1, int(std::floor((maxy - g.oy) / g.res)) + 1);
  for (int iy = iy0; iy <= iy1; ++iy)
    for (int ix = ix0; ix <= ix1; ++ix) {
      uint8_t& cell = (*band)[size_t(iy) * g.w + ix];
      if (cell) continue;
      if (Overlaps(poly, g.ox + ix * g.res, g.oy + iy * g.res, g.res)) cell = 1;
    }
}

}  // namespace

Result<FloorPlan> RasterizeFloorPlan(const World& world, const FloorPlanParams& params) {
  const double res = params.resolution_m;
  if (!(std::isfinite(res) && res > 0.0))
    return InvalidArgument("floor plan resolution must be positive, got " + std::to_string(res));
  if (!(std::isfinite(params.min_z_m) && std::isfinite(params.max_z_m) &&
        params.min_z_m < params.max_z_m))
    return InvalidArgument("floor plan height band must have min_z < max_z");
  if (!(std::isfinite(params.floor_min_z_m) && params.floor_min_z_m < params.min_z_m))
    return InvalidArgument("floor plan floor_min_z must be below min_z");
  const Mesh& mesh = world.mesh;
  if (mesh.empty())
    return InvalidArgument("cannot rasterize a floor plan: the world has no triangles");

  double minx = std::numeric_limits<double>::infinity(), miny = minx, maxx = -minx, maxy = -minx;
  for (const auto& t : mesh.triangles)
    for (uint32_t v : t) {
      if (v >= mesh.positions.size())
        return InvalidArgument("cannot rasterize a floor plan: triangle index out of range");
      const auto& p = mesh.positions[v];
      if (!p.allFinite())
        return InvalidArgument("cannot rasterize a floor plan: non-finite vertex");
      minx = std::min(minx, double(p.x()));
      maxx = std::max(maxx, double(p.x()));
      miny = std::min(miny, double(p.y()));
      maxy = std::max(maxy, double(p.y()));
    }
  // Cell corners on multiples of the resolution, one spare cell around.
  const double kx0 = std::floor(minx / res) - 1, ky0 = std::floor(miny / res) - 1;
  const double kx1 = std::ceil(maxx / res) + 1, ky1 = std::ceil(maxy / res) + 1;
  const double cells = (kx1 - kx0) * (ky1 - ky0);
  if (!(cells <= 64.0 * 1024 * 1024))
    return InvalidArgument("floor plan would have " + std::to_string(int64_t(cells)) +
                           " cells: resolution too fine for a world this large");
  Grid g{kx0 * res, ky0 * res, res, int(kx1 - kx0), int(ky1 - ky0)};
  const size_t n = size_t(g.w) * g.h;
  std::vector<uint8_t> band(n, 0), floor(n, 0), up_back(n, 0);
  std::vector<double> up_z(n, std::numeric_limits<double>::infinity());
  const double zb0 = params.min_z_m, zb1 = params.max_z_m, zf = params.floor_min_z_m;

  for (const auto& tri : mesh.triangles) {
    P3 v[3];
    for (int k = 0; k < 3; ++k) {
      const auto& p = mesh.positions[tri[k]];
      v[k] = {double(p.x()), double(p.y()), double(p.z())};
    }
    const double zmin = std::min({v[0][2], v[1][2], v[2][2]});
    const double zmax = std::max({v[0][2], v[1][2], v[2][2]});
    if (zmax >= zb0 && zmin <= zb1) {
      std::vector<P3> poly = {v[0], v[1], v[2]};
      if (zmin < zb0) poly = ClipZ(poly, zb0, true);
      if (!poly.empty() && zmax > zb1) poly = ClipZ(poly, zb1, false);
      if (!poly.empty()) {
        std::vector<P2> flat;
        for (const P3& p : poly) flat.push_back({p[0], p[1]});
        MarkBand(flat, g, &band);
      }
    }
    // Coverage of cell centres by the triangle's projection (not for vertical triangles).
    const double ux = v[1][0] - v[0][0], uy = v[1][1] - v[0][1], uz = v[1][2] - v[0][2];
    const double wx = v[2][0] - v[0][0], wy = v[2][1] - v[0][1], wz = v[2][2] - v[0][2];
    const double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (!(len > 0.0) || std::abs(nz) < 1e-6 * len) continue;
    const bool is_floor_like = std::abs(nz) >= 0.7 * len && zmin < zb0 && zmax >= zf;
    const bool reaches_up = params.fill_solids && zmax > zb0;
    if (!is_floor_like && !reaches_up) continue;
    const double bx0 = std::min({v[0][0], v[1][0], v[2][0]}),
                 bx1 = std::max({v[0][0], v[1][0], v[2][0]});
    const double by0 = std::min({v[0][1], v[1][1], v[2][1]}),
                 by1 = std::max({v[0][1], v[1][1], v[2][1]});
    const int ix0 = std::max(0, int(std::ceil((bx0 - g.ox) / res - 0.5)));
    const int ix1 = std::min(g.w - 1, int(std::floor((bx1 - g.ox) / res - 0.5)));
    const int iy0 = std::max(0, int(std::ceil((by0 - g.oy) / res - 0.5)));
    const int iy1 = std::min(g.h - 1, int(std::floor((by1 - g.oy) / res - 0.5)));
    const double sign = nz > 0 ? 1.0 : -1.0;  // projected orientation
    const double tol = 1e-9 * std::abs(nz);
    for (int iy = iy0; iy <= iy1; ++iy)
      for (int ix = ix0; ix <= ix1; ++ix) {
        const double cx = g.ox + (ix + 0.5) * res, cy = g.oy + (iy + 0.5) * res;
        bool inside = true;
        for (int e = 0; e < 3 && inside; ++e) {
          const P3& a = v[e];
          const P3& b = v[(e + 1) % 3];
          const double edge = (b[0] - a[0]) * (cy - a[1]) - (b[1] - a[1]) * (cx - a[0]);
          if (sign * edge < -tol) inside = false;
        }
        if (!inside) continue;
        const double z = v[0][2] - (nx * (cx - v[0][0]) + ny * (cy - v[0][1])) / nz;
        const size_t i = size_t(iy) * g.w + ix;
        if (is_floor_like && z >= zf && z < zb0) floor[i] = 1;
        if (reaches_up && z > zb0) {
          if (z < up_z[i] - 1e-7) {
            up_z[i] = z;
            up_back[i] = nz > 0;
          } else if (z <= up_z[i] + 1e-7 && nz < 0) {
            up_back[i] = 0;  // coincident faces: the front one wins
          }
        }
      }
  }

  FloorPlan plan;
  plan.origin_W = Eigen::Vector2f(float(g.ox), float(g.oy));
  plan.resolution_m = params.resolution_m;
  plan.width = g.w;
  plan.height = g.h;
  plan.cells.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (band[i] || (params.fill_solids && up_back[i]))
      plan.cells[i] = PlanCell::kObstacle;
    else if (floor[i])
      plan.cells[i] = PlanCell::kFree;
    else
      plan.cells[i] = PlanCell::kOutside;
  }
  return plan;
}

}  // namespace voxplan
