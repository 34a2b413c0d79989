#pragma once
// Depth files the way datasets ship them besides 16-bit PNG, written with OpenCV's imgcodecs for
// the tests of io/depth_image.h (tests/io) and of `fuse` over them (tests/system): 32-bit float
// TIFF and OpenEXR in metres, 16-bit TIFF in units, and whatever else a test wants refused.
// Include only from test files built with OpenCV's include folder as a system folder.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "core/image.h"

namespace voxplan::test {

inline cv::Mat ToMat(const DepthImage& depth) {
  cv::Mat m(depth.height, depth.width, CV_32FC1);
  for (int y = 0; y < depth.height; ++y)
    for (int x = 0; x < depth.width; ++x) m.at<float>(y, x) = depth.at(x, y);
  return m;
}

// Writes `m` with OpenCV (the type from the extension), asserting that it did.
inline void WriteWithOpenCv(const std::filesystem::path& path, const cv::Mat& m,
                            const std::vector<int>& params = {}) {
  std::filesystem::create_directories(path.parent_path());
  ASSERT_TRUE(cv::imwrite(path.string(), m, params)) << path;
}

// Float metres as a .tif/.tiff/.exr (32-bit float samples; lossless).
inline void WriteFloatDepth(const std::filesystem::path& path, const DepthImage& depth) {
  WriteWithOpenCv(path, ToMat(depth));
}

// Raw 16-bit units as a TIFF.
inline void WriteDepthTiff16(const std::filesystem::path& path, int width, int height,
                             const std::vector<uint16_t>& units) {
  cv::Mat m(height, width, CV_16UC1);
  for (int i = 0; i < width * height; ++i) m.at<uint16_t>(i / width, i % width) = units[size_t(i)];
  WriteWithOpenCv(path, m);
}

}  // namespace voxplan::test
