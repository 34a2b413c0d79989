#pragma once
// Line-oriented text files as the dataset readers, trajectory files and evaluators read them:
// tokens per line, `file:line: ...` errors, number parsing and timestamp checks. A UTF-8 BOM
// and CRLF endings are accepted; blank lines, `#` lines and trailing `# ...` comments skipped.
#include <string>
#include <vector>

#include "core/status.h"

namespace voxplan {

struct TextLine {
  int number = 0;  // 1-based line in the file
  std::vector<std::string> tokens;
};

struct TextFile {
  std::string path;
  std::vector<TextLine> lines;  // only lines with tokens
};

// Refuses control characters (a binary file) with `path:line`.
Result<TextFile> ReadTextFile(const std::string& path);

// A kCorruptData status "file:line: what".
Status LineError(const std::string& file, int line, const std::string& what);

// `v` with up to 10 significant digits, for messages.
std::string NumberText(double v);
// A float as the double with the same shortest decimal form (0.02f -> 0.02, not 0.0199999...),
// for JSON outputs.
double ShortestDouble(float value);

// A whole token as a double (a leading '+' accepted; NaN and inf parse: callers check).
bool ParseDouble(const std::string& token, double& out);
// Tokens [first, first + count) of `line` as numbers into out[0 .. count).
Status ParseNumbers(const TextFile& f, const TextLine& line, size_t first, size_t count,
                    double* out);
// `line` has exactly `count` tokens; `format` names them in the error.
Status ExpectTokens(const TextFile& f, const TextLine& line, size_t count,
                    const std::string& format);

// Timestamps must be finite, non-negative and strictly increasing.
class TimestampChecker {
 public:
  Status Check(const TextFile& f, const TextLine& line, double t);

 private:
  bool has_prev_ = false;
  double prev_ = 0.0;
};

}  // namespace voxplan
