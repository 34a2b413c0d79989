// Top-down run pictures and SVG plots: pixels and text read back at known places.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "viewer_offscreen/svg_plot.h"
#include "viewer_offscreen/top_down.h"

namespace voxplan {
namespace {

// A 10 m x 6 m floor at 0.1 m: free, with a wall column at x in [5, 5.1) and one unknown cell.
TopDownRaster Floor() {
  TopDownRaster r;
  r.origin_W = Eigen::Vector2f(-1.f, -1.f);
  r.resolution_m = 0.1f;
  r.classes = Image<uint8_t>(100, 60, uint8_t(TopDownClass::kFree));
  for (int y = 0; y < 60; ++y) r.classes.at(60, y) = uint8_t(TopDownClass::kObstacle);
  r.classes.at(10, 50) = uint8_t(TopDownClass::kUnknown);
  return r;
}

// Pixel centre of world point p at 2 pixels per 0.1 m cell (rows run from +y down).
Eigen::Vector2i Pixel(const TopDownRaster& r, const Eigen::Vector2f& p_W, int height_px) {
  const Eigen::Vector2f q = (p_W - r.origin_W) / r.resolution_m * 2.f;
  return {int(q.x()), height_px - 1 - int(q.y())};
}

TEST(TopDown, OverlayLinesAndDotsLieUnderThePaths) {
  // A planner's drawings: a line along y = 2 crossing a path along x = 3, and a dot at (7, 1).
  const TopDownRaster floor = Floor();
  TopDownPath path;
  path.points_W = {{3.f, 0.f}, {3.f, 4.f}};
  TopDownOverlay overlay;
  const uint32_t line = PackRgb(10, 200, 30), dot = PackRgb(200, 10, 30);
  overlay.strokes.push_back({{{0.f, 2.f}, {4.5f, 2.f}}, line, true});
  overlay.strokes.push_back({{{7.f, 1.f}}, dot, false});
  auto image = RenderTopDown(floor, {path}, {}, overlay);
  ASSERT_TRUE(image.ok()) << image.status().message();
  const Eigen::Vector2i on_line = Pixel(floor, {1.f, 2.f}, 120);
  EXPECT_EQ(image->at(on_line.x(), on_line.y()), line);
  const Eigen::Vector2i crossing = Pixel(floor, {3.f, 2.f}, 120);
  EXPECT_EQ(image->at(crossing.x(), crossing.y()), RobotColor(0));  // the path over it
  const Eigen::Vector2i at_dot = Pixel(floor, {7.f, 1.f}, 120);
  EXPECT_EQ(image->at(at_dot.x(), at_dot.y()), dot);
  // Without the overlay the same pixels are floor.
  auto plain = RenderTopDown(floor, {path});
  ASSERT_TRUE(plain.ok());
  EXPECT_NE(plain->at(on_line.x(), on_line.y()), line);
  // A non-finite overlay point is refused.
  overlay.strokes.push_back({{{std::nanf(""), 0.f}}, dot, false});
  EXPECT_FALSE(RenderTopDown(floor, {path}, {}, overlay).ok());
}

TEST(TopDown, CellsPathsAndMarksLandWhereTheWorldSaysTheyAre) {
  const TopDownRaster floor = Floor();
  TopDownParams params;
  TopDownPath a, b;
  a.points_W = {{0.f, 0.f}, {3.f, 0.f}, {3.f, 3.f}};
  b.points_W = {{0.f, 4.f}, {4.f, 4.f}};
  b.views = {{{2.f, 4.f}, 0.f}};
  auto image = RenderTopDown(floor, {a, b}, params);
  ASSERT_TRUE(image.ok()) << image.status().message();
  ASSERT_EQ(image->width, 200);
  ASSERT_EQ(image->height, 120);

  // Raster classes, y up: the wall column at cell x = 60, the unknown cell (10, 50).
  EXPECT_EQ(image->at(121, 60), params.class_colors[2]);
  EXPECT_EQ(image->at(21, 120 - 1 - 101), params.class_colors[0]);
  EXPECT_EQ(image->at(150, 10), params.class_colors[1]);

  // Mid-segment pixels carry each robot's colour; start ring and end square too.
  const Eigen::Vector2i mid_a = Pixel(floor, {1.5f, 0.f}, 120);
  EXPECT_EQ(image->at(mid_a.x(), mid_a.y()), RobotColor(0));
  const Eigen::Vector2i up_a = Pixel(floor, {3.f, 1.5f}, 120);
  EXPECT_EQ(image->at(up_a.x(), up_a.y()), RobotColor(0));
  const Eigen::Vector2i mid_b = Pixel(floor, {3.f, 4.f}, 120);
  EXPECT_EQ(image->at(mid_b.x(), mid_b.y()), RobotColor(1));
  const Eigen::Vector2i end_b = Pixel(floor, {4.f, 4.f}, 120);
  EXPECT_EQ(image->at(end_b.x(), end_b.y()), RobotColor(1));
  // The ring around robot 0's start is hollow: its centre shows the path, its rim the colour.
  const Eigen::Vector2i start_a = Pixel(floor, {0.f, 0.f}, 120);
  EXPECT_EQ(image->at(start_a.x(), start_a.y() - params.mark_radius_px), RobotColor(0));
  // Away from everything: free floor.
  const Eigen::Vector2i empty = Pixel(floor, {1.5f, 2.f}, 120);
  EXPECT_EQ(image->at(empty.x(), empty.y()), params.class_colors[1]);
  // The task view's dot is a darker shade of robot 1's colour.
  const Eigen::Vector2i view = Pixel(floor, {2.f, 4.f}, 120);
  const uint32_t dot = image->at(view.x(), view.y());
  EXPECT_NE(dot, RobotColor(1));
  EXPECT_LT(Red(dot) + Green(dot) + Blue(dot),
            Red(RobotColor(1)) + Green(RobotColor(1)) + Blue(RobotColor(1)));
}

TEST(TopDown, SameInputSamePixels) {
  TopDownPath a;
  a.points_W = {{0.f, 0.f}, {3.3f, 1.7f}, {6.f, 2.f}};
  a.views = {{{3.3f, 1.7f}, 1.f}};
  auto first = RenderTopDown(Floor(), {a});
  auto second = RenderTopDown(Floor(), {a});
  ASSERT_TRUE(first.ok() && second.ok());
  EXPECT_EQ(first->data, second->data);
}

TEST(TopDown, RefusesBadInput) {
  EXPECT_FALSE(RenderTopDown(TopDownRaster{}, {}).ok());
  TopDownRaster bad_res = Floor();
  bad_res.resolution_m = 0.f;
  EXPECT_FALSE(RenderTopDown(bad_res, {}).ok());
  TopDownParams huge;
  huge.pixels_per_cell = 1000;
  EXPECT_FALSE(RenderTopDown(Floor(), {}, huge).ok());
  TopDownPath nan_path;
  nan_path.points_W = {{0.f, 0.f}, {NAN, 1.f}};
  auto refused = RenderTopDown(Floor(), {nan_path});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("robot 0"), std::string::npos);
}

TEST(SvgPlot, NiceTicksAreRoundAndCoverTheRange) {
  const std::vector<double> unit = NiceTicks(0.0, 1.0, 5);
  ASSERT_EQ(unit.size(), 6u);
  for (size_t i = 0; i < unit.size(); ++i) EXPECT_NEAR(unit[i], 0.2 * double(i), 1e-12);
  const std::vector<double> t = NiceTicks(3.0, 97.0, 6);
  ASSERT_GE(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[1] - t[0], 20.0);
  EXPECT_LE(t.front(), 20.0);
  EXPECT_GE(t.back(), 80.0);
}

TEST(SvgPlot, OnePolylinePerSeriesPiecewiseAtGaps) {
  PlotParams params;
  params.title = "coverage <vs> time";
  params.x_label = "time (s)";
  params.y_label = "coverage";
  params.y_min = 0.0, params.y_max = 1.0;
  std::vector<PlotSeries> series = {{"robot 0", {0, 10, 20, 30}, {0, 0.3, 0.6, 0.9}},
                                    {"robot 1", {0, 10, 20, 30}, {0, 0.2, NAN, 0.5}}};
  auto svg = SvgLinePlot(series, params);
  ASSERT_TRUE(svg.ok()) << svg.status().message();
  const std::regex polyline("<polyline");
  const auto n = std::distance(std::sregex_iterator(svg->begin(), svg->end(), polyline),
                               std::sregex_iterator());
  EXPECT_EQ(n, 3);  // robot 1's NaN splits its line in two
  EXPECT_NE(svg->find("coverage &lt;vs&gt; time"), std::string::npos);
  EXPECT_NE(svg->find("robot 1"), std::string::npos);
  EXPECT_EQ(svg->rfind("</svg>\n"), svg->size() - 7);
  // Same input, same bytes.
  EXPECT_EQ(*svg, *SvgLinePlot(series, params));
}

TEST(SvgPlot, RefusesMismatchedOrEmptySeries) {
  EXPECT_FALSE(SvgLinePlot({{"a", {0, 1}, {0}}}, {}).ok());
  EXPECT_FALSE(SvgLinePlot({{"a", {NAN}, {1}}}, {}).ok());
  EXPECT_FALSE(SvgLinePlot({}, {}).ok());
}

}  // namespace
}  // namespace voxplan

namespace voxplan {
namespace {

TEST(SvgTimeline, DrawsOneRectanglePerSpanInItsCategorysColourAndRefusesBadSpans) {
  TimelineParams tp;
  tp.title = "modes";
  tp.categories = {{"explorer", PackRgb(255, 0, 0)}, {"idle", PackRgb(0, 0, 255)}};
  const std::vector<TimelineRow> rows = {{"r0", {{0.0, 10.0, 0}, {10.0, 15.0, 1}}},
                                         {"r1", {{0.0, 15.0, 0}}}};
  Result<std::string> svg = SvgTimeline(rows, tp);
  ASSERT_TRUE(svg.ok()) << svg.status().message();
  size_t red = 0, blue = 0;
  for (size_t at = 0; (at = svg->find("fill=\"#ff0000\"", at)) != std::string::npos; ++at) ++red;
  for (size_t at = 0; (at = svg->find("fill=\"#0000ff\"", at)) != std::string::npos; ++at) ++blue;
  EXPECT_EQ(red, 3u);                       // two spans and the legend
  EXPECT_EQ(blue, 2u);                      // one span and the legend
  EXPECT_EQ(*SvgTimeline(rows, tp), *svg);  // same input, same bytes
  EXPECT_FALSE(SvgTimeline({{"r0", {{0.0, 1.0, 2}}}}, tp).ok());
  EXPECT_FALSE(SvgTimeline({{"r0", {{2.0, 1.0, 0}}}}, tp).ok());
  EXPECT_FALSE(SvgTimeline({{"r0", {}}}, tp).ok());
}

}  // namespace
}  // namespace voxplan
