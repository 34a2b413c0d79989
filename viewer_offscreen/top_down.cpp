#include "viewer_offscreen/top_down.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace voxplan {
namespace {

constexpr int kMaxSidePx = 16384;

class Canvas {
 public:
  explicit Canvas(ColorImage& image) : image_(image) {}

  void Disc(float cx, float cy, float radius, uint32_t color) {
    const int x0 = int(std::floor(cx - radius)), x1 = int(std::ceil(cx + radius));
    const int y0 = int(std::floor(cy - radius)), y1 = int(std::ceil(cy + radius));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float dx = float(x) + 0.5f - cx, dy = float(y) + 0.5f - cy;
        if (dx * dx + dy * dy <= radius * radius) Put(x, y, color);
      }
  }

  void Ring(float cx, float cy, float radius, float width, uint32_t color) {
    const float r_out = radius + 0.5f * width, r_in = radius - 0.5f * width;
    const int x0 = int(std::floor(cx - r_out)), x1 = int(std::ceil(cx + r_out));
    const int y0 = int(std::floor(cy - r_out)), y1 = int(std::ceil(cy + r_out));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float dx = float(x) + 0.5f - cx, dy = float(y) + 0.5f - cy;
        const float d2 = dx * dx + dy * dy;
        if (d2 <= r_out * r_out && d2 >= r_in * r_in) Put(x, y, color);
      }
  }

  // A segment of the given width: every pixel whose centre is within width / 2 of it.
  void Line(const Eigen::Vector2f& a, const Eigen::Vector2f& b, float width, uint32_t color) {
    const float half = 0.5f * width;
    const int x0 = int(std::floor(std::min(a.x(), b.x()) - half));
    const int x1 = int(std::ceil(std::max(a.x(), b.x()) + half));
    const int y0 = int(std::floor(std::min(a.y(), b.y()) - half));
    const int y1 = int(std::ceil(std::max(a.y(), b.y()) + half));
    const Eigen::Vector2f ab = b - a;
    const float len2 = ab.squaredNorm();
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2f p(float(x) + 0.5f, float(y) + 0.5f);
        const float t = len2 > 0.f ? std::clamp((p - a).dot(ab) / len2, 0.f, 1.f) : 0.f;
        if ((p - (a + t * ab)).squaredNorm() <= half * half) Put(x, y, color);
      }
  }

  void Square(float cx, float cy, float half, uint32_t color) {
    for (int y = int(std::floor(cy - half)); y < int(std::ceil(cy + half)); ++y)
      for (int x = int(std::floor(cx - half)); x < int(std::ceil(cx + half)); ++x) Put(x, y, color);
  }

 private:
  void Put(int x, int y, uint32_t color) {
    if (x >= 0 && y >= 0 && x < image_.width && y < image_.height) image_.at(x, y) = color;
  }
  ColorImage& image_;
};

uint32_t Darker(uint32_t c) {
  return PackRgb(uint8_t(Red(c) * 3 / 5), uint8_t(Green(c) * 3 / 5), uint8_t(Blue(c) * 3 / 5));
}

}  // namespace

uint32_t RobotColor(size_t k) {
  static constexpr uint32_t kPalette[10] = {0x00b4771f, 0x000e7fff, 0x002ca02c, 0x002827d6,
                                            0x00bd6794, 0x004b568c, 0x00c277e3, 0x007f7f7f,
                                            0x0022bdbc, 0x00cfbe17};  // Tableau 10, packed RGBX
  return kPalette[k % 10];
}

Result<ColorImage> RenderTopDown(const TopDownRaster& raster, const std::vector<TopDownPath>& paths,
                                 const TopDownParams& params, const TopDownOverlay& overlay) {
  const Image<uint8_t>& classes = raster.classes;
  if (classes.empty() || classes.width <= 0 || classes.height <= 0)
    return InvalidArgument("top-down render: the floor raster is empty");
  if (!(raster.resolution_m > 0.f) || !std::isfinite(raster.resolution_m) ||
      !raster.origin_W.allFinite())
    return InvalidArgument(
        "top-down render: the raster needs a positive resolution and "
        "a finite origin");
  if (params.pixels_per_cell < 1 || classes.width > kMaxSidePx / params.pixels_per_cell ||
      classes.height > kMaxSidePx / params.pixels_per_cell)
    return InvalidArgument("top-down render: " + std::to_string(classes.width) + "x" +
                           std::to_string(classes.height) + " cells at " +
                           std::to_string(params.pixels_per_cell) + " pixels per cell exceed " +
                           std::to_string(kMaxSidePx) + " pixels a side");
  for (size_t r = 0; r < paths.size(); ++r) {
    for (const Eigen::Vector2f& p : paths[r].points_W)
      if (!p.allFinite())
        return InvalidArgument("top-down render: robot " + std::to_string(r) +
                               "'s path has a non-finite point");
    for (const TopDownView& v : paths[r].views)
      if (!v.position_W.allFinite() || !std::isfinite(v.yaw_rad))
        return InvalidArgument("top-down render: robot " + std::to_string(r) +
                               " has a non-finite task view");
  }

  for (const TopDownOverlay::Stroke& stroke : overlay.strokes)
    for (const Eigen::Vector2f& p : stroke.points_W)
      if (!p.allFinite()) return InvalidArgument("top-down render: an overlay point is not finite");

  const int s = params.pixels_per_cell;
  ColorImage image(classes.width * s, classes.height * s);
  for (int y = 0; y < classes.height; ++y)
    for (int x = 0; x < classes.width; ++x) {
      const uint32_t c = params.class_colors[classes.at(x, y) & 7];
      const int row = (classes.height - 1 - y) * s;  // +y up
      for (int dy = 0; dy < s; ++dy) std::fill_n(&image.at(x * s, row + dy), s, c);
    }

  // World metres to image pixels (continuous, pixel centres at +0.5).
  const float px_per_m = float(s) / raster.resolution_m;
  auto to_px = [&](const Eigen::Vector2f& p_W) {
    const Eigen::Vector2f q = (p_W - raster.origin_W) * px_per_m;
    return Eigen::Vector2f(q.x(), float(image.height) - q.y());
  };

  Canvas canvas(image);
  const float width = float(params.line_width_px), mark = float(params.mark_radius_px);
  // The overlay over the floor, thinner than the paths; then the paths, then the marks over
  // every path, so no path hides another robot's marks.
  for (const TopDownOverlay::Stroke& stroke : overlay.strokes) {
    const std::vector<Eigen::Vector2f>& pts = stroke.points_W;
    if (stroke.polyline) {
      for (size_t i = 1; i < pts.size(); ++i)
        canvas.Line(to_px(pts[i - 1]), to_px(pts[i]), std::max(1.f, 0.5f * width), stroke.color);
    } else {
      for (const Eigen::Vector2f& p : pts) {
        const Eigen::Vector2f c = to_px(p);
        canvas.Disc(c.x(), c.y(), 0.5f * mark, stroke.color);
      }
    }
  }
  for (size_t r = 0; r < paths.size(); ++r) {
    const std::vector<Eigen::Vector2f>& pts = paths[r].points_W;
    for (size_t i = 1; i < pts.size(); ++i)
      canvas.Line(to_px(pts[i - 1]), to_px(pts[i]), width, RobotColor(r));
  }
  for (size_t r = 0; r < paths.size(); ++r) {
    const uint32_t color = RobotColor(r), dark = Darker(color);
    for (const TopDownView& v : paths[r].views) {
      // A dot with a short stroke along the camera heading (image y points down).
      const Eigen::Vector2f c = to_px(v.position_W);
      const Eigen::Vector2f tip =
          c + 2.f * mark * Eigen::Vector2f(std::cos(v.yaw_rad), -std::sin(v.yaw_rad));
      canvas.Line(c, tip, std::max(1.f, 0.5f * width), dark);
      canvas.Disc(c.x(), c.y(), 0.5f * mark, dark);
    }
    const std::vector<Eigen::Vector2f>& pts = paths[r].points_W;
    if (pts.empty()) continue;
    const Eigen::Vector2f start = to_px(pts.front()), end = to_px(pts.back());
    canvas.Ring(start.x(), start.y(), mark, width, color);  // start: a ring
    canvas.Square(end.x(), end.y(), mark * 0.8f, color);    // end: a filled square
  }
  return image;
}

}  // namespace voxplan
