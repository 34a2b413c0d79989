#include "io/tum_trajectory.h"

#include <Eigen/Geometry>
#include <cstdio>

#include "io/file_util.h"
#include "io/text_file.h"

namespace voxplan {

Result<TumTrajectory> ReadTumTrajectory(const std::string& path, std::vector<std::string>* warnings,
                                        const std::string& fields) {
  Result<TextFile> file = ReadTextFile(path);
  if (!file.ok()) return file.status();
  TumTrajectory trajectory;
  trajectory.source = path;
  TimestampChecker checker;
  for (const TextLine& line : file->lines) {
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 8, fields));
    double v[8];
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, line, 0, 8, v));
    VOXPLAN_RETURN_IF_ERROR(checker.Check(*file, line, v[0]));
    bool renormalised = false;
    Result<Pose3d> pose =
        PoseFromTranslationQuaternion({v[1], v[2], v[3]}, v[4], v[5], v[6], v[7], &renormalised);
    if (!pose.ok()) return LineError(path, line.number, pose.status().message());
    if (renormalised && warnings)
      warnings->push_back(path + ":" + std::to_string(line.number) + ": quaternion norm " +
                          NumberText(Eigen::Vector4d(v[4], v[5], v[6], v[7]).norm()) +
                          " renormalised");
    trajectory.timestamps_s.push_back(v[0]);
    trajectory.T_W_C.push_back(*pose);
  }
  if (trajectory.T_W_C.empty()) return CorruptData(path + ": no poses");
  return trajectory;
}

Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3d>& T_W_C) {
  if (timestamps_s.size() != T_W_C.size()) {
    return InvalidArgument(path + ": " + std::to_string(timestamps_s.size()) + " timestamps but " +
                           std::to_string(T_W_C.size()) + " poses");
  }
  std::string text = "# timestamp tx ty tz qx qy qz qw (T_W_C, camera-to-world)\n";
  char line[256];
  for (size_t i = 0; i < T_W_C.size(); ++i) {
    Eigen::Quaterniond q(T_W_C[i].linear());
    q.normalize();
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // one of the two equal quaternions, stably
    const Eigen::Vector3d& t = T_W_C[i].translation();
    std::snprintf(line, sizeof(line), "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", timestamps_s[i],
                  t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    text += line;
  }
  return WriteFileAtomically(path, text);
}

Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3f>& T_W_C) {
  std::vector<Pose3d> poses;
  poses.reserve(T_W_C.size());
  for (const Pose3f& T : T_W_C) poses.push_back(T.cast<double>());
  return WriteTumTrajectory(path, timestamps_s, poses);
}

}  // namespace voxplan
