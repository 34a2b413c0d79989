#include "io/text_file.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string_view>

#include "io/file_util.h"

namespace voxplan {

std::string NumberText(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

double ShortestDouble(float value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.7g", double(value));
  return std::strtod(text, nullptr);
}

Status LineError(const std::string& file, int line, const std::string& what) {
  return CorruptData(file + ":" + std::to_string(line) + ": " + what);
}

Result<TextFile> ReadTextFile(const std::string& path) {
  auto content = ReadFileToString(path);
  if (!content.ok()) return content.status();
  const std::string& s = *content;
  TextFile file;
  file.path = path;
  size_t pos = s.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  int number = 0;
  while (pos < s.size()) {
    size_t end = s.find('\n', pos);
    if (end == std::string::npos) end = s.size();
    std::string_view line(s.data() + pos, end - pos);
    pos = end + 1;
    ++number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    TextLine parsed;
    parsed.number = number;
    size_t i = 0;
    while (i < line.size()) {
      const unsigned char c = static_cast<unsigned char>(line[i]);
      if (c == ' ' || c == '\t') {
        ++i;
        continue;
      }
      if (c < 0x20 || c == 0x7f)
        return LineError(path, number, "unexpected control character (not a text file?)");
      if (c == '#') break;  // a comment to the end of the line
      size_t j = i;
      while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
      parsed.tokens.emplace_back(line.substr(i, j - i));
      i = j;
    }
    if (parsed.tokens.empty()) continue;
    file.lines.push_back(std::move(parsed));
  }
  return file;
}

bool ParseDouble(const std::string& token, double& out) {
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (first != last && *first == '+') ++first;
  const auto [ptr, ec] = std::from_chars(first, last, out);
  return ec == std::errc() && ptr == last;
}

Status ParseNumbers(const TextFile& f, const TextLine& line, size_t first, size_t count,
                    double* out) {
  for (size_t k = 0; k < count; ++k) {
    if (!ParseDouble(line.tokens[first + k], out[k]))
      return LineError(f.path, line.number,
                       "'" + line.tokens[first + k] + "' is not a number (token " +
                           std::to_string(first + k + 1) + ")");
  }
  return Status::Ok();
}

Status ExpectTokens(const TextFile& f, const TextLine& line, size_t count,
                    const std::string& format) {
  if (line.tokens.size() != count)
    return LineError(f.path, line.number,
                     "expected " + std::to_string(count) + " fields '" + format + "', found " +
                         std::to_string(line.tokens.size()));
  return Status::Ok();
}

Status TimestampChecker::Check(const TextFile& f, const TextLine& line, double t) {
  if (!std::isfinite(t)) return LineError(f.path, line.number, "timestamp is not finite");
  if (t < 0.0) return LineError(f.path, line.number, "negative timestamp " + NumberText(t));
  if (has_prev_ && t == prev_)
    return LineError(f.path, line.number, "duplicate timestamp " + NumberText(t));
  if (has_prev_ && t < prev_)
    return LineError(
        f.path, line.number,
        "timestamp " + NumberText(t) + " out of order (after " + NumberText(prev_) + ")");
  prev_ = t;
  has_prev_ = true;
  return Status::Ok();
}

}  // namespace voxplan
