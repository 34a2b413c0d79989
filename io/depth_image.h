#pragma once
// Depth images in every file type the dataset readers take: 16-bit PNG (image_io.h), TIFF (.tif,
// .tiff: 16-bit unsigned or 32-bit float samples, in strips or tiles) through libtiff, and OpenEXR
// (.exr: one 32-bit or 16-bit float channel, of any name, scanline or tiled) through OpenEXR. The
// type comes from the file name's extension; 16-bit integer files hold units of 1 / depth_scale
// metres, float files hold metres (the depth scale does not apply). Headers are read and checked
// by voxplan before either library sees the file, so that a wrong kind of file is refused with a
// message naming it and a corrupt one is caught before it is decoded. Every error names the file;
// nothing is printed (libtiff's messages are caught per call, OpenEXR's exceptions too).
#include <string>

#include "core/image.h"
#include "core/status.h"

namespace voxplan {

enum class DepthFileType { kPng, kTiff, kExr };

// .tif / .tiff -> kTiff, .exr -> kExr (any case); every other name is read as a PNG, as before.
DepthFileType DepthFileTypeOf(const std::string& path);
const char* DepthFileTypeName(DepthFileType type);  // "PNG", "TIFF", "EXR"

// What a depth file's header says, read without decoding pixels.
struct DepthFileHeader {
  DepthFileType type = DepthFileType::kPng;
  int width = 0;
  int height = 0;
  int bits = 16;        // bits per sample: 16 (integer, or EXR half float) or 32 (float)
  bool metres = false;  // float samples, in metres: the depth scale does not apply
  // "16-bit PNG", "16-bit TIFF", "32-bit float TIFF", "32-bit float EXR", "16-bit float EXR".
  std::string Encoding() const;
};

// Reads and checks the header: refuses every file ReadDepthImage would refuse for its kind
// (Unsupported: multi-channel, 8-bit, signed or 64-bit samples, EXR channel types other than
// float) or its header (CorruptData: not the format its name says, sizes beyond 16384 per side,
// tiles far larger than the image, directories or chunks outside the file).
Result<DepthFileHeader> ReadDepthHeader(const std::string& path);

// Decodes a depth image into metres (0 = invalid). 16-bit samples: value / depth_scale, as
// ReadDepthPng converts them, so a 16-bit TIFF decodes to the same floats as the same values in
// a PNG. Float samples are metres as they are; NaN, infinite and negative values become 0.
// `header`, when given, receives the file's header.
Result<DepthImage> ReadDepthImage(const std::string& path, double depth_scale,
                                  DepthFileHeader* header = nullptr);

}  // namespace voxplan
