#include "viewer_offscreen/shading.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "core/parallel.h"

namespace voxplan {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool IsHit(float depth) { return depth > 0.0f && std::isfinite(depth); }

bool IsFinite(const Eigen::Vector3f& v) { return v.allFinite(); }

uint8_t ToByte(float x) { return uint8_t(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)); }

uint32_t PackUnit(const Eigen::Vector3f& rgb) {
  return PackRgb(ToByte(rgb.x()), ToByte(rgb.y()), ToByte(rgb.z()));
}

Eigen::Vector3f Unpack(uint32_t c) { return Eigen::Vector3f(Red(c), Green(c), Blue(c)) / 255.0f; }

template <typename T>
bool SizeMatches(const Image<T>& image, int width, int height) {
  return image.empty() || (image.width == width && image.height == height);
}

// Rows in parallel: each pixel is independent, so the output does not depend on threads.
template <typename F>
void ForEachRow(int height, F&& f) {
  ParallelFor(size_t(height), 8, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) f(int(v));
  });
}

// Near and far of the depth colour map: the 1st and 99th percentiles, so a few stray far
// pixels do not squeeze the rest of the image into one colour.
std::pair<float, float> AutoDepthRange(const DepthImage& depth) {
  std::vector<float> valid;
  valid.reserve(depth.data.size());
  for (float d : depth.data)
    if (IsHit(d)) valid.push_back(d);
  if (valid.empty()) return {0.0f, 1.0f};
  auto percentile = [&](double q) {
    const size_t k = size_t(q * double(valid.size() - 1));
    std::nth_element(valid.begin(), valid.begin() + ptrdiff_t(k), valid.end());
    return valid[k];
  };
  const float near_m = percentile(0.01);
  const float far_m = percentile(0.99);
  return {near_m, std::max(far_m, near_m + 1e-3f)};
}

}  // namespace

Result<ShadeMode> ParseShadeMode(std::string_view name) {
  if (name == "shaded") return ShadeMode::kShaded;
  if (name == "normals") return ShadeMode::kNormals;
  if (name == "colour" || name == "color") return ShadeMode::kColour;
  if (name == "depth") return ShadeMode::kDepth;
  return InvalidArgument("unknown shading mode '" + std::string(name) +
                         "' (use shaded, normals, colour or depth)");
}

const char* ShadeModeName(ShadeMode mode) {
  switch (mode) {
    case ShadeMode::kShaded:
      return "shaded";
    case ShadeMode::kNormals:
      return "normals";
    case ShadeMode::kColour:
      return "colour";
    case ShadeMode::kDepth:
      return "depth";
  }
  return "unknown";
}

uint32_t ViridisColor(float t) {
  // matplotlib's viridis at 10 evenly spaced stops (#440154 ... #FDE725); linear
  // interpolation between them stays within a few levels of the full 256-entry table.
  static constexpr std::array<std::array<uint8_t, 3>, 10> kStops = {{{0x44, 0x01, 0x54},
                                                                     {0x48, 0x28, 0x78},
                                                                     {0x3E, 0x4A, 0x89},
                                                                     {0x31, 0x68, 0x8E},
                                                                     {0x26, 0x82, 0x8E},
                                                                     {0x1F, 0x9E, 0x89},
                                                                     {0x35, 0xB7, 0x79},
                                                                     {0x6D, 0xCD, 0x59},
                                                                     {0xB4, 0xDE, 0x2C},
                                                                     {0xFD, 0xE7, 0x25}}};
  if (!std::isfinite(t)) t = 0.0f;
  const float x = std::clamp(t, 0.0f, 1.0f) * float(kStops.size() - 1);
  const size_t i = std::min(size_t(x), kStops.size() - 2);
  const float f = x - float(i);
  auto mix = [&](int c) {
    return uint8_t(std::lround((1.0f - f) * kStops[i][c] + f * kStops[i + 1][c]));
  };
  return PackRgb(mix(0), mix(1), mix(2));
}

Image<Eigen::Vector3f> VerticesFromDepth(const DepthImage& depth, const PinholeCamera& camera,
                                         const Pose3f& T_W_C) {
  Image<Eigen::Vector3f> vertex_W(depth.width, depth.height, Eigen::Vector3f::Constant(kNaN));
  ForEachRow(depth.height, [&](int v) {
    for (int u = 0; u < depth.width; ++u) {
      const float z = depth.at(u, v);
      if (IsHit(z)) vertex_W.at(u, v) = T_W_C * camera.Unproject(float(u), float(v), z);
    }
  });
  return vertex_W;
}

Image<Eigen::Vector3f> NormalsFromVertices(const Image<Eigen::Vector3f>& vertex_W,
                                           const Eigen::Vector3f& camera_centre_W) {
  const int w = vertex_W.width, h = vertex_W.height;
  Image<Eigen::Vector3f> normal_W(w, h, Eigen::Vector3f::Constant(kNaN));
  // The difference towards whichever neighbour is closer in space: across a depth edge that
  // is the one on the same surface.
  auto valid = [&](int u, int v) {
    return u >= 0 && v >= 0 && u < w && v < h && vertex_W.at(u, v).allFinite();
  };
  // The difference towards whichever neighbour (along du, dv) is closer in space: across a
  // depth edge that is the one on the same surface.
  auto tangent = [&](int u, int v, int du, int dv, Eigen::Vector3f* t) {
    const Eigen::Vector3f& p = vertex_W.at(u, v);
    const bool has_prev = valid(u - du, v - dv), has_next = valid(u + du, v + dv);
    if (!has_prev && !has_next) return false;
    const Eigen::Vector3f d_prev =
        has_prev ? Eigen::Vector3f(p - vertex_W.at(u - du, v - dv)) : Eigen::Vector3f::Zero();
    const Eigen::Vector3f d_next =
        has_next ? Eigen::Vector3f(vertex_W.at(u + du, v + dv) - p) : Eigen::Vector3f::Zero();
    *t = has_prev && (!has_next || d_prev.squaredNorm() <= d_next.squaredNorm()) ? d_prev : d_next;
    return true;
  };
  ForEachRow(h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3f& p = vertex_W.at(u, v);
      if (!IsFinite(p)) continue;
      Eigen::Vector3f t_u, t_v;
      if (!tangent(u, v, 1, 0, &t_u) || !tangent(u, v, 0, 1, &t_v)) continue;
      Eigen::Vector3f n = t_u.cross(t_v);
      const float length = n.norm();
      if (!(length > 0.0f)) continue;
      n /= length;
      if (n.dot(camera_centre_W - p) < 0.0f) n = -n;
      normal_W.at(u, v) = n;
    }
  });
  return normal_W;
}

Result<ColorImage> Shade(const SurfaceImages& surface, const PinholeCamera& camera,
                         const Pose3f& T_W_C, ShadeMode mode, const ShadeParams& params) {
  const int w = surface.depth.width, h = surface.depth.height;
  if (surface.depth.empty()) return InvalidArgument("Shade: empty depth image");
  if (camera.width != w || camera.height != h) {
    return InvalidArgument("Shade: camera is " + std::to_string(camera.width) + "x" +
                           std::to_string(camera.height) + " but the depth image is " +
                           std::to_string(w) + "x" + std::to_string(h));
  }
  if (!SizeMatches(surface.vertex_W, w, h) || !SizeMatches(surface.normal_W, w, h) ||
      !SizeMatches(surface.color, w, h)) {
    return InvalidArgument("Shade: vertex, normal and colour images must match the depth size");
  }
  const bool has_color = !surface.color.empty();
  ColorImage out(w, h, mode == ShadeMode::kDepth ? PackRgb(0, 0, 0) : params.background);

  if (mode == ShadeMode::kDepth) {
    // Plain locals, not a structured binding: the lambda below captures far_m (clang 14).
    float near_m = params.depth_near_m;
    float far_m = params.depth_far_m;
    if (!(near_m < far_m)) std::tie(near_m, far_m) = AutoDepthRange(surface.depth);
    const float inv_range = 1.0f / (far_m - near_m);
    ForEachRow(h, [&](int v) {
      for (int u = 0; u < w; ++u) {
        const float z = surface.depth.at(u, v);
        // Near is bright: what is closest catches the eye first.
        if (IsHit(z)) out.at(u, v) = ViridisColor((far_m - z) * inv_range);
      }
    });
    return out;
  }
  if (mode == ShadeMode::kColour) {
    ForEachRow(h, [&](int v) {
      for (int u = 0; u < w; ++u) {
        if (IsHit(surface.depth.at(u, v)))
          out.at(u, v) = has_color ? surface.color.at(u, v) : params.neutral;
      }
    });
    return out;
  }

  // Shaded and normals need geometry; fill in what the renderer did not give.
  Image<Eigen::Vector3f> computed_vertex, computed_normal;
  const Image<Eigen::Vector3f>* vertex_W = &surface.vertex_W;
  if (vertex_W->empty()) {
    computed_vertex = VerticesFromDepth(surface.depth, camera, T_W_C);
    vertex_W = &computed_vertex;
  }
  const Eigen::Vector3f eye_W = T_W_C.translation();
  const Image<Eigen::Vector3f>* normal_W = &surface.normal_W;
  if (normal_W->empty()) {
    computed_normal = NormalsFromVertices(*vertex_W, eye_W);
    normal_W = &computed_normal;
  }

  ForEachRow(h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const float z = surface.depth.at(u, v);
      if (!IsHit(z)) continue;
      Eigen::Vector3f p = vertex_W->at(u, v);
      if (!IsFinite(p)) p = T_W_C * camera.Unproject(float(u), float(v), z);
      // Headlight: light and eye at the camera centre.
      Eigen::Vector3f to_eye = eye_W - p;
      const float eye_distance = to_eye.norm();
      to_eye = eye_distance > 0.0f ? Eigen::Vector3f(to_eye / eye_distance)
                                   : Eigen::Vector3f(T_W_C.linear() * -Eigen::Vector3f::UnitZ());
      Eigen::Vector3f n = normal_W->at(u, v);
      const bool has_normal = IsFinite(n) && n.squaredNorm() > 0.0f;
      if (mode == ShadeMode::kNormals) {
        if (has_normal)
          out.at(u, v) = PackUnit(n.normalized() * 0.5f + Eigen::Vector3f::Constant(0.5f));
        continue;
      }
      n = has_normal ? Eigen::Vector3f(n.normalized()) : to_eye;
      float n_dot_l = n.dot(to_eye);
      if (n_dot_l < 0.0f) {  // a back face (open meshes): light it like the front
        n = -n;
        n_dot_l = -n_dot_l;
      }
      const Eigen::Vector3f reflected = 2.0f * n_dot_l * n - to_eye;
      const float spec = std::pow(std::max(0.0f, reflected.dot(to_eye)), params.shininess);
      const Eigen::Vector3f albedo = Unpack(has_color ? surface.color.at(u, v) : params.neutral);
      const Eigen::Vector3f rgb = albedo * (params.ambient + params.diffuse * n_dot_l) +
                                  Eigen::Vector3f::Constant(params.specular * spec);
      out.at(u, v) = PackUnit(rgb);
    }
  });
  return out;
}

}  // namespace voxplan
